"""Headless Chromium (Debian's ``chromium``, installed by ``make browser``)
driven over its DevTools protocol with the ``websockets`` client.

    with Browser(tmp_path / "chromium") as b:
        page = b.open("http://localhost:8766/")
        page.wait_for("document.querySelector('#robot-1') !== null")
        x = page.eval("document.querySelector('#robot-1').dataset.x")
        page.screenshot(tmp_path / "view.png")

The browser runs with a new empty profile and everything that would reach
out to the network switched off (this machine's network is closed).
A missing browser is an error naming the command that installs it, never a skip.
"""
from __future__ import annotations

import base64
import itertools
import json
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic",
         "--disable-extensions", "--disable-default-apps", "--no-default-browser-check", "--mute-audio"]
INSTALL = "make browser  (as root: apt-get install -y chromium; as anyone else: sudo apt-get install -y chromium)"


class BrowserError(RuntimeError):
    pass


def chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    raise BrowserError(f"no chromium on PATH: the browser test needs Debian's chromium; install it with {INSTALL}")


class Page:
    """One tab, reached through the browser's connection with a session id."""

    def __init__(self, browser: Browser, session: str, target: str):
        self.browser, self.session, self.target = browser, session, target

    def send(self, method: str, **params):
        return self.browser.send(method, session=self.session, **params)

    def eval(self, expression: str):
        """The value of a JavaScript expression in the page (JSON-able)."""
        r = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise BrowserError(f"{expression}: {r['exceptionDetails'].get('text')} "
                               f"{r['exceptionDetails'].get('exception', {}).get('description', '')}")
        return r["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 20.0, poll: float = 0.1, between=None):
        """Until ``expression`` is truthy (its value); ``between()`` is called between polls.
        An expression that throws (the page is not there yet) counts as false until the timeout."""
        end = time.monotonic() + timeout
        while True:
            try:
                value, error = self.eval(expression), None
            except BrowserError as exc:
                value, error = None, exc
            if value:
                return value
            if time.monotonic() > end:
                raise BrowserError(f"timed out after {timeout:g} s waiting for: {expression}"
                                   + (f" (last: {error})" if error else ""))
            if between is not None:
                between()
            else:
                time.sleep(poll)

    def screenshot(self, path: Path) -> Path:
        data = self.send("Page.captureScreenshot", format="png", captureBeyondViewport=True)["data"]
        path = Path(path)
        path.write_bytes(base64.b64decode(data))
        return path


class Browser:
    """A headless Chromium process and its DevTools connection (see the module doc)."""

    def __init__(self, profile_dir: Path, width: int = 1400, height: int = 1100, start_timeout: float = 120.0):
        self.profile = Path(profile_dir)
        if self.profile.exists():
            shutil.rmtree(self.profile)
        self.profile.mkdir(parents=True)
        self.size = (width, height)
        self.log = open(self.profile.parent / f"{self.profile.name}.log", "wb")  # noqa: SIM115 - closed in close()
        self.proc = subprocess.Popen(
            [chromium(), *FLAGS, f"--user-data-dir={self.profile}", "--remote-debugging-port=0",
             f"--window-size={width},{height}", "about:blank"],
            stdout=self.log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
        self._ids = itertools.count(1)
        self.ws = None
        try:
            self._connect(start_timeout)
        except BaseException:
            self.close()
            raise

    def _connect(self, timeout: float) -> None:
        from websockets.sync.client import connect
        port_file = self.profile / "DevToolsActivePort"
        end = time.monotonic() + timeout
        while not (port_file.exists() and len(port_file.read_text().splitlines()) >= 2):
            if self.proc.poll() is not None:
                raise BrowserError(f"chromium exited ({self.proc.returncode}); see {self.log.name}")
            if time.monotonic() > end:
                raise BrowserError(f"chromium did not open its DevTools port in {timeout:g} s; see {self.log.name}")
            time.sleep(0.05)
        port, path = port_file.read_text().splitlines()[:2]
        self.ws = connect(f"ws://127.0.0.1:{port}{path}", max_size=None, open_timeout=10)

    def send(self, method: str, session: str | None = None, timeout: float = 60.0, **params) -> dict:
        msg_id = next(self._ids)
        msg = {"id": msg_id, "method": method, "params": params}
        if session is not None:
            msg["sessionId"] = session
        self.ws.send(json.dumps(msg))
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise BrowserError(f"no answer to {method} in {timeout:g} s")
            reply = json.loads(self.ws.recv(timeout=left))
            if reply.get("id") == msg_id:
                if "error" in reply:
                    raise BrowserError(f"{method}: {reply['error'].get('message')}")
                return reply.get("result", {})

    def open(self, url: str) -> Page:
        target = self.send("Target.createTarget", url="about:blank")["targetId"]
        session = self.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        page = Page(self, session, target)
        page.send("Page.enable")
        page.send("Runtime.enable")
        w, h = self.size
        page.send("Emulation.setDeviceMetricsOverride", width=w, height=h, deviceScaleFactor=1, mobile=False)
        page.send("Page.navigate", url=url)
        page.wait_for(f"document.readyState === 'complete' && location.href.startsWith({json.dumps(url)})",
                      timeout=120)
        return page

    def close(self) -> None:
        if self.ws is not None:
            try:
                self.send("Browser.close", timeout=5)
            except Exception:
                pass
            try:
                self.ws.close()
            except Exception:
                pass
            self.ws = None
        if self.proc.poll() is None:
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                pass
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)         # the group this browser leads, nothing else
        except ProcessLookupError:
            pass
        self.proc.wait(5)
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
