"""The walk's constants, each with what it was chosen from (measured where it says so): timing, margins, costs,
the scene's and the controller's settings shared by the walking modules."""

from __future__ import annotations

INTEGRATORS = ("implicitfast", "RK4", "Euler", "implicit")


STAND_HEIGHT_MIN: float = 0.02  # [m] the lowest stand_height a walk takes
# [m] the highest stand_height a walk's parameter takes: two links of a robot file's longest (10 m). A robot's own
# reach refuses the rest (kinematics.legged.tallest_stance): the hexabot's 0.1833 m, a tall robot file's more.
STAND_HEIGHT_MAX: float = 20.0

# [m] load_sharing=force with level_body=on: the least distance of the body's centre inside the feet down over the
# planned cycle. Measured on quadbot-walk's crawl at 0.05 m/s: duty 0.75 (0 mm) and 0.8 (1.2 mm) rolled 32 and 15 deg
# peak to peak and lost 64 and 76 % of the speed; 0.85 (2.4 mm), 0.88 (3.3 mm) and 0.9 (3.6 mm) walked within 5 %
# and 1.2 deg (the hexabot's gaits: 84-95 mm).
FORCE_LEVEL_MARGIN: float = 0.002

SETTLE_TIME: float = 0.5  # [s] standing on the neutral stance before the gait clock starts

SPEED_MARGIN: float = 0.9  # planned joint speeds must stay below this fraction of max_joint_speed

LOADED_FRACTION: float = 0.05  # a foot counts as loaded above this fraction of the robot's weight


CSV_FIXED_COLUMNS: int = 13  # columns of timeseries.csv besides the legs' (6 each: contact, 2 forces, 3 joints)

# Cost of a run for budget.check_run_cost, measured on the 2-core development machine (10 s vs 60 s
# walks): seconds per physics step (controller + mj_step: 25 us in bench.py, with a margin for a loaded
# machine), seconds per recorded row (contact replay, derived columns; the CSV is counted apart), peak
# bytes per recorded row.
RUN_COST: tuple[float, float, float] = (30e-6, 40e-6, 2000.0)

# Seconds per physics step with terrain or the ground-finding controller (rough ground: 42-44 us in bench.py).
TERRAIN_STEP_SECONDS: float = 50e-6

KERB_PLATE_CLEARANCE: float = 0.005  # [m] a kerb stays this far below the plate's underside at the stand height

MEASURE_TIME: float = 0.1  # [s] shortest walk after the ramp that the metrics are measured over

FALL_TILT_DEG: float = 45.0  # body tilt beyond which the robot has fallen over

# NoSlip iterations on uneven ground. MuJoCo's soft friction lets a foot under a steady tangential
# load creep: the standing robot slid down a 10 deg slope at 0.9-1.8 mm/s with the defaults. Two
# NoSlip passes (MuJoCo's remedy for slow slippage, run after the main solve) bring that to 0.005 mm/s
# and 0.001-0.004 mm/s on 1 cm rough ground; impratio=100 did it too (0.009 mm/s) but its elliptic
# cones took 6.7 Newton iterations and 73 line searches a step: bare mj_step 69 us on rough ground
# against 31.5 us with NoSlip (median of 15 walks, 3 gaits x 5 seeds). The flat floor keeps the
# defaults (its published results were measured with them; there is no steady tangential load there).
TERRAIN_NOSLIP_ITERATIONS: int = 2

SCENE_EXTENT: float = 2.0  # [m] <statistic extent> of a scene with terrain (what MuJoCo computes for the flat one)

SLOPE_CAMERA_DISTANCE: float = 0.9  # [m] the slope video's camera: beside the body, across the slope

SLOPE_CAMERA_HEIGHT: float = 0.08  # [m] above the body's centre of mass (low: the ground's tilt shows)

# Limit on the commanded joint acceleration (resolved-rate step). It smooths what the position feedback
# asks when a foot is stopped short (a kerb's edge, a bump): with 400 rad/s^2 the 3 cm kerb walk stumbled
# (16 deg of roll), with 200 it climbs. But it must never clip the gait's own plan: the wave gait's 1/6-period
# swing needs 266 rad/s^2 at 0.05 m/s and 364 at 0.095 m/s (period 1 s). Clipped at 200, the wave at
# 0.095 m/s lost 5.0 % of its speed on flat ground (-0.6 % unclipped), and 6.8..8.5 % with up to 2.8 deg of
# pitch on 1 cm rough ground (-2.0..-3.6 %, <= 1.2 deg unclipped; measured). A servo's 1.5 N*m gives a swinging leg
# 336, 414 and 479 rad/s^2 (coxa, femur, tibia: torque over the mass-matrix diagonal, armature included).
ACCELERATION_LIMIT: float = 200.0  # [rad/s^2] the limit, unless the planned cycle needs more

# [m] With the pad (feet=pad) and sensed touchdown, a touch while the swing's target is less than this above its end
# height is the pad's first contact (it begins 0.8 mm above the sphere: legged_mjcf.FOOT_PAD_MARGIN), not an early
# touchdown: the swing goes on to its end, as with planned touchdown. Measured (load_sharing=force feet=pad
# swing=quintic, flat, 8 s, tripod / ripple / wave): without it 20 / 10 / 8 foot bounces, the landing foot rebounding
# when its target stopped at the first touch; with it 0 / 0 / 0. 1 mm and 2 mm gave the same figures on the flat and
# with terrain_map=on on 1 cm rough ground (seeds 0, 1), and without the map figures within those seeds' spread.
PAD_EARLY_BAND: float = 0.0015

REFLEX_LIFT: float = 1.0  # the elevator reflex lifts a blocked swing foot this many step heights higher

ACCELERATION_HEADROOM: float = 1.2  # the limit is at least this times the planned cycle's peak joint acceleration

# A gait with two feet down (the quadbot's trot) balances on the line between them: the feet must lie on opposite
# sides of the body's centre, seen from it at least this far apart. Measured (quadbot-trot, 4 s at 0.1 m/s, fell
# false throughout): diagonal pairs 180 deg -1.3 %, the hips shifted 0.12 m forward 141 deg -45 %, 0.2 m 108 deg
# -131 % (backwards), 'names' listing lf, rf, rr, lr (a pace) 103 deg backwards, lf, lr, rr, rf (a bound) 77 deg -94 %.
TWO_FEET_APART_DEG: float = 120.0  # [deg]
