"""One headless Chromium for a test module, driven over the DevTools protocol on a pipe (--remote-debugging-pipe:
JSON messages ending in a NUL byte, commands on the browser's fd 3, answers and events on its fd 4), so that each
page is a new tab in a running browser instead of a browser launched per page (about 3 s each here)."""

from __future__ import annotations

import base64
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

FLAGS = ["--headless=new", "--disable-gpu", "--no-sandbox", "--hide-scrollbars", "--no-first-run",
         "--disable-extensions", "--mute-audio"]  # fmt: skip


class Browser:
    """A running headless Chromium; `tab()` opens a page in a new tab of it."""

    def __init__(self, binary: str) -> None:
        # The browser reads commands on its fd 3 and writes answers and events on its fd 4: a small Python program
        # moves the pipe ends there and execs it (no preexec_fn, which can deadlock a child forked from a process
        # with threads, as an xdist worker is; dash's redirections take one-digit fds only).
        commands_read, self._commands = os.pipe()
        self._answers, answers_write = os.pipe()
        env = dict(os.environ, HOME=os.environ.get("HOME", "/tmp"))
        self._log = tempfile.TemporaryFile()  # the browser's stderr, for the messages (a pipe could fill and block it)
        shim = "import os, sys; a = sys.argv; os.dup2(int(a[1]), 3); os.dup2(int(a[2]), 4); os.execv(a[3], a[3:])"
        self.proc = subprocess.Popen(
            [sys.executable, "-S", "-c", shim, str(commands_read), str(answers_write),
             binary, *FLAGS, "--remote-debugging-pipe", "about:blank"],
            env=env, pass_fds=(commands_read, answers_write), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=self._log,
        )  # fmt: skip
        os.close(commands_read)
        os.close(answers_write)
        self._next_id = 0
        self._buffer = b""
        self._events: list[dict] = []

    def close(self) -> None:
        try:
            self.send("Browser.close", timeout=10)
        except (OSError, RuntimeError, TimeoutError):  # already gone or not answering: killed below
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self._commands)
        os.close(self._answers)
        self._log.close()

    def log(self) -> str:
        """The end of the browser's stderr."""
        self._log.seek(0)
        return self._log.read()[-2000:].decode(errors="replace")

    def _read_message(self, deadline: float) -> dict:
        import select

        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._answers], [], [], left)[0]:
                raise TimeoutError(f"Chromium did not answer in time: {self.log()}")
            chunk = os.read(self._answers, 1 << 20)
            if not chunk:
                raise RuntimeError(f"Chromium exited (code {self.proc.poll()}): {self.log()}")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 60) -> dict:
        """Sends one command and returns its result (the events that arrive meanwhile are kept for `wait_event`)."""
        self._next_id += 1
        message: dict[str, Any] = {"id": self._next_id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        os.write(self._commands, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            answer = self._read_message(deadline)
            if answer.get("id") == self._next_id:
                if "error" in answer:
                    raise RuntimeError(f"{method}: {answer['error']}")
                return answer["result"]
            if "method" in answer:
                self._events.append(answer)

    def wait_event(self, method: str, session: str, timeout: float = 60) -> dict:
        deadline = time.monotonic() + timeout
        while True:
            for event in self._events:
                if event["method"] == method and event.get("sessionId") == session:
                    self._events.remove(event)
                    return event["params"]
            answer = self._read_message(deadline)
            if "method" in answer:
                self._events.append(answer)

    def tab(self, url: str, width: int = 800, height: int = 600) -> Tab:
        """A new tab of this viewport size [CSS px] showing `url`, after its load event (images loaded)."""
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        tab = Tab(self, target, session)
        self.send("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session)  # fmt: skip
        self.send("Page.enable", session=session)
        self.send("Page.navigate", {"url": url}, session)
        self.wait_event("Page.loadEventFired", session)
        return tab


class Tab:
    def __init__(self, browser: Browser, target: str, session: str) -> None:
        self.browser, self.target, self.session = browser, target, session

    def evaluate(self, expression: str) -> Any:
        result = self.browser.send("Runtime.evaluate", {"expression": expression, "returnByValue": True}, self.session)
        return result["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 60) -> Any:
        """The value of `expression` once it is not null (polled every 50 ms)."""
        deadline = time.monotonic() + timeout
        while (value := self.evaluate(expression)) is None:
            if time.monotonic() > deadline:
                raise TimeoutError(f"{expression} stayed null for {timeout} s: {self.browser.log()}")
            time.sleep(0.05)
        return value

    def screenshot(self, out: Path) -> None:
        """The viewport as a PNG file."""
        data = self.browser.send("Page.captureScreenshot", {"format": "png"}, self.session)["data"]
        out.write_bytes(base64.b64decode(data))

    def close(self) -> None:
        self.browser.send("Target.closeTarget", {"targetId": self.target})

    def __enter__(self) -> Tab:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
