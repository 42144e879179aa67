"""Steering a walk live from the keyboard (`hexabot-sim view hexabot-walk`): keys change a Steering command source.

Keys (GLFW key codes, as MuJoCo's viewer hands them to its key callback; shift read from the window):
  Up / Down               forward speed +- SPEED_STEP
  Left / Right            yaw rate +- YAW_STEP (counter-clockwise / clockwise)
  shift + Left / Right    sideways speed +- SPEED_STEP (crab to the left / right)
  Page Up / Page Down     stand height +- HEIGHT_STEP
  keypad 1 / 2 / 3        the six-legged gaits tripod / ripple / wave (the quadruped's: crawl / trot)
  keypad 0                stop (zero twist)
The digits above the letters are MuJoCo's viewer's own (they show and hide geom groups: `2` hid the robot's
visual geoms, measured), so the gaits are on the keypad. A change the legs cannot deliver with the gait and
heights asked for (walking.parameters.feasibility, the same check as a run's) is refused and said so in the overlay.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from hexabot_sim.control.commands import Steering
from hexabot_sim.control.gait import Command

KEY_RIGHT, KEY_LEFT, KEY_DOWN, KEY_UP, KEY_PAGE_UP, KEY_PAGE_DOWN = 262, 263, 264, 265, 266, 267
KEY_KP_0, KEY_KP_1, KEY_KP_2, KEY_KP_3 = 320, 321, 322, 323

SPEED_STEP: float = 0.02  # [m/s] a key press's change of vx or vy
YAW_STEP: float = 0.1  # [rad/s] a key press's change of the yaw rate
HEIGHT_STEP: float = 0.005  # [m] a key press's change of the stand height

HELP = (
    ("Up Down", f"walk faster / slower ({SPEED_STEP:g} m/s)"),
    ("Left Right", f"turn left / right ({YAW_STEP:g} rad/s)"),
    ("shift+Left Right", "crab left / right"),
    ("PgUp PgDn", f"body up / down ({HEIGHT_STEP * 1000:g} mm)"),
)


class KeySteering:
    """Keys -> a Steering's target, checked against what the legs can deliver.

    Args:
        p: The walk's parameters (the start: its command, gait and heights).
        steering: The command source the controller queries.
        check: feasibility(params) -> '' or why not (walking.parameters.feasibility).
    """

    def __init__(self, p: Any, steering: Steering, check: Callable[[Any], str]) -> None:
        self.p, self.steering, self.check = p, steering, check
        self.gait_keys = dict(zip((KEY_KP_1, KEY_KP_2, KEY_KP_3), p.gaits(), strict=False))
        self.note = ""  # why the last key was refused
        # The duty the controller walks: the walk's own `duty` (0: the gait's) until a key changes the gait, the new
        # gait's own after (the controller switches to the gait as the robot's gaits define it).
        self.duty = p.duty

    def key(self, code: int, shift: bool) -> bool:
        """Applies a key press; False if it is not a steering key (the viewer's own then)."""
        s = self.steering
        c = s.target
        vx, vy, w, stand, gait = c.vx, c.vy, c.yaw_rate, s.stand_height, s.gait
        if code == KEY_UP:
            vx += SPEED_STEP
        elif code == KEY_DOWN:
            vx -= SPEED_STEP
        elif code in (KEY_LEFT, KEY_RIGHT):
            sign = 1.0 if code == KEY_LEFT else -1.0
            if shift:
                vy += sign * SPEED_STEP
            else:
                w += sign * YAW_STEP
        elif code in (KEY_PAGE_UP, KEY_PAGE_DOWN):
            stand += HEIGHT_STEP if code == KEY_PAGE_UP else -HEIGHT_STEP
        elif code in self.gait_keys:
            gait = self.gait_keys[code]
            now = s.now  # the gait changes at once: it must carry the twist in force too
            problem = self._problem(float(now[0]), float(now[1]), float(now[2]), s.stand_height, gait, self._duty(gait))
            if problem:
                self.note = f"{gait} refused at the speed in force (slow down first): {problem.split(';')[0]}"
                return True
        elif code == KEY_KP_0:
            vx = vy = w = 0.0
        else:
            return False
        vx, vy, w, stand = (round(v, 6) + 0.0 for v in (vx, vy, w, stand))
        problem = self._problem(vx, vy, w, stand, gait, self._duty(gait))
        if problem:
            self.note = f"refused: {problem.split(';')[0]}"
            return True
        self.duty = self._duty(gait)
        s.target, s.gait, s.stand_height = Command(vx, vy, w), gait, stand
        self.note = ""
        return True

    @property
    def help(self) -> tuple[tuple[str, str], ...]:
        """The keys' help rows for the viewer."""
        digits = " ".join(str(k - KEY_KP_0) for k in self.gait_keys)
        return (*HELP, (f"keypad {digits} 0", f"{' / '.join(self.gait_keys.values())}, stop"))

    def _duty(self, gait: str) -> float:
        """The duty the controller will walk `gait` at: the one in force, or a new gait's own (0)."""
        return self.duty if gait == self.steering.gait else 0.0

    def _problem(self, vx: float, vy: float, w: float, stand: float, gait: str, duty: float) -> str:
        try:
            q = dataclasses.replace(self.p, vx=vx, vy=vy, yaw_rate=w, gait=gait, stand_height=stand, duty=duty)
        except ValueError as e:
            return str(e)
        return self.check(q)

    def text(self) -> str:
        """The overlay's line: the command asked for and in force, or why the last key was refused."""
        s = self.steering
        c = s.target
        now = s.now
        line = (
            f"steer: vx {c.vx:+.2f} vy {c.vy:+.2f} m/s, yaw {c.yaw_rate:+.2f} rad/s, {s.gait}, stand "
            f"{s.stand_height * 1000:.0f} mm\nin force: vx {now[0]:+.3f} vy {now[1]:+.3f} m/s, yaw {now[2]:+.3f} rad/s"
        )
        return f"{line}\n{self.note[:120]}" if self.note else line
