"""Progress on stderr: a redrawn bar on a terminal, plain lines in a log."""

from __future__ import annotations

import sys
import time
from typing import Any


class ProgressBar:
    """Progress on stderr: a redrawn bar on a terminal, else a plain line every PLAIN_EVERY percent and at least
    every PLAIN_SECONDS while it is called (logs: a run allowed to take an hour was silent for 15 min between
    quarters)."""

    PLAIN_EVERY: int = 25  # [%]
    PLAIN_SECONDS: float = 60.0  # [s]

    def __init__(self, label: str, stream: Any = None) -> None:
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._last = -1
        self._last_line = time.monotonic()

    def __call__(self, done: int, total: int) -> None:
        percent = 100 * done // max(total, 1)
        if not self.tty:
            step = percent // self.PLAIN_EVERY * self.PLAIN_EVERY
            now = time.monotonic()
            if step > self._last or now - self._last_line >= self.PLAIN_SECONDS:
                self._last, self._last_line = max(step, self._last), now
                self._write(f"{self.label}: {percent}% ({done}/{total})\n")
            return
        if percent == self._last and done != total:
            return
        self._last = percent
        filled = percent * 30 // 100
        self._write(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {percent:3d}% ({done}/{total})")
        if done >= total:
            self._write("\n")

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # progress is a courtesy: a broken stderr must not stop the run
            pass


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds // 60:.0f} min {seconds % 60:02.0f} s"
    return f"{seconds // 3600:.0f} h {seconds % 3600 // 60:02.0f} min"


class SweepProgress(ProgressBar):
    """Cells done / total with the elapsed time and an ETA; in logs a plain line every 10 % or PLAIN_SECONDS."""

    PLAIN_EVERY: int = 10  # [%]

    def __init__(self, label: str, stream: Any = None) -> None:
        super().__init__(label, stream)
        self._start = self._last_line

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        elapsed = now - self._start
        percent = 100 * done // max(total, 1)
        eta = f", ETA {_duration(elapsed / done * (total - done))}" if 0 < done < total else ""
        text = f"{done}/{total} cells, {_duration(elapsed)}{eta}"
        if not self.tty:
            step = percent // self.PLAIN_EVERY * self.PLAIN_EVERY
            if step > self._last or now - self._last_line >= self.PLAIN_SECONDS or done == total != 0 > self._last:
                self._last, self._last_line = max(step, self._last), now
                self._write(f"{self.label}: {percent}% ({text})\n")
            return
        filled = percent * 30 // 100
        self._write(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {percent:3d}% ({text})\x1b[K")
        if done >= total:
            self._write("\n")
