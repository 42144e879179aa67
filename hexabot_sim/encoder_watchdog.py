"""The video encoder's watchdog: a frame write that blocks (an encoder that stopped reading) is ended by stopping the
encoder, so a run reports no video instead of hanging (render.render_video)."""

from __future__ import annotations

import math
import os
import signal
import threading
import time


class EncoderWatchdog:
    """Stops this process's encoder, and whatever it started, if one frame write blocks longer than `timeout` [s].

    The blocked write then fails (broken pipe) and the video is reported as not written, with the reason.
    Processes are found in /proc (Linux); elsewhere the watchdog only watches.
    """

    def __init__(self, exe: str, timeout: float) -> None:
        self.exe = exe
        self.timeout = timeout
        self.fired = False
        self._deadline = math.inf
        self._before: set[int] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="encoder-watchdog", daemon=True)

    def __enter__(self) -> EncoderWatchdog:
        # The writer starts its encoder at the first frame: a child that was not there now is the encoder.
        self._before = {pid for pid, (ppid, _) in self._processes().items() if ppid == os.getpid()}
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def arm(self) -> None:
        self._deadline = time.monotonic() + self.timeout

    def disarm(self) -> None:
        self._deadline = math.inf

    def _watch(self) -> None:
        while not self._stop.wait(min(1.0, self.timeout / 4)):
            if time.monotonic() > self._deadline:
                self.fired = True
                for pid in self._children():
                    try:
                        os.kill(pid, signal.SIGKILL)
                    except OSError:
                        pass
                return

    def _children(self) -> list[int]:
        """The encoder's PIDs and their descendants: this process's children started as the encoder (argv[0], or
        argv[1] for a script) or since the watchdog began (an encoder that exec'd something else), and every
        process under them (a wrapper's child holding the pipe kept the run blocked after the wrapper was killed)."""
        processes = self._processes()
        me, exe = os.getpid(), os.fsencode(self.exe)
        found = [
            pid for pid, (ppid, argv) in processes.items() if ppid == me and (exe in argv or pid not in self._before)
        ]
        queue = list(found)
        while queue:
            parent = queue.pop()
            below = [pid for pid, (ppid, _) in processes.items() if ppid == parent and pid not in found]
            found += below
            queue += below
        return found

    @staticmethod
    def _processes() -> dict[int, tuple[int, list[bytes]]]:
        """{pid: (parent pid, argv[:2])} of every process /proc shows (empty where there is no /proc)."""
        out: dict[int, tuple[int, list[bytes]]] = {}
        try:
            entries = os.listdir("/proc")
        except OSError:
            return out
        for entry in entries:
            if not entry.isdigit():
                continue
            try:
                with open(f"/proc/{entry}/stat", "rb") as f:
                    ppid = int(f.read().rsplit(b")", 1)[1].split()[1])
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    argv = f.read().split(b"\0")[:2]
            except (OSError, ValueError, IndexError):
                continue
            out[int(entry)] = (ppid, argv)
        return out
