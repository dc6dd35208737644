"""Headless Chromium, driven through the DevTools protocol on a pipe: how the kit prints decks to PDF and
measures them as a projector would show them (``cs451 slides pdf``, ``cs451 slides check``, the slide tests).

A pipe (``--remote-debugging-pipe``) needs no websocket and no extra package, and the browser runs with the
network unreachable (a proxy on a closed port, every host name unresolvable): a deck that tried to fetch
something fails to show it rather than reaching out.
"""
from __future__ import annotations

import base64
import fcntl
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import KitError

if TYPE_CHECKING:
    from PIL import Image


def find_chromium() -> str | None:
    """The Chromium (or Chrome) on PATH, or None."""
    return next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                             shutil.which("google-chrome")) if p), None)


def chromium_or_refuse() -> str:
    found = find_chromium()
    if found is None:
        raise KitError("no Chromium on PATH: the decks are printed and measured in headless Chromium "
                       "(Debian/Ubuntu: apt-get install chromium; macOS: install Google Chrome and put it on PATH)")
    return found


#: Runs Chromium with the pipe's ends as fds 3 (it reads) and 4 (it writes), as --remote-debugging-pipe expects.
PIPE_EXEC = ("import os, sys; os.dup2(int(sys.argv[1]), 3); os.dup2(int(sys.argv[2]), 4); "
             "os.execv(sys.argv[3], sys.argv[3:])")


class Chromium:
    """Headless Chromium driven through the DevTools protocol on a pipe (fds 3 and 4), with no network."""

    def __init__(self, width: int = 1280, height: int = 720, executable: str | None = None):
        self.profile = Path(tempfile.mkdtemp(prefix="cs451-chromium-"))
        to_r, to_w = os.pipe()
        from_r, from_w = os.pipe()
        for_child = []
        for fd in (to_r, from_w):     # above 3 and 4, so that putting them there cannot clobber them
            for_child.append(fcntl.fcntl(fd, fcntl.F_DUPFD, 64))
            os.close(fd)
        to_r, from_w = for_child
        args = [executable or chromium_or_refuse(), "--headless", "--remote-debugging-pipe", "--no-sandbox", "--disable-gpu", "--no-first-run",
                "--no-default-browser-check", f"--user-data-dir={self.profile}", "--proxy-server=127.0.0.1:9",
                "--host-resolver-rules=MAP * ~NOTFOUND", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--disable-extensions", "--disable-default-apps",
                "--mute-audio", "--hide-scrollbars", "--disable-dev-shm-usage", f"--window-size={width},{height}",
                "about:blank"]
        self.proc = subprocess.Popen([sys.executable, "-c", PIPE_EXEC, str(to_r), str(from_w), *args],
                                     pass_fds=(to_r, from_w), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_r)
        os.close(from_w)
        self.out = os.fdopen(to_w, "wb", buffering=0)
        self.inp = os.fdopen(from_r, "rb", buffering=0)
        self.ids = 0
        self.replies: dict[int, dict] = {}
        self.events: list[dict] = []
        self.cv = threading.Condition()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()
        self.size = (width, height)

    def _read(self) -> None:
        buf = b""
        while True:
            chunk = self.inp.read(1 << 16)
            if not chunk:
                with self.cv:
                    self.cv.notify_all()
                return
            buf += chunk
            while b"\0" in buf:
                raw, buf = buf.split(b"\0", 1)
                msg = json.loads(raw)
                with self.cv:
                    (self.replies.__setitem__(msg["id"], msg) if "id" in msg else self.events.append(msg))
                    self.cv.notify_all()

    def call(self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 60) -> dict:
        self.ids += 1
        mid = self.ids
        msg = {"id": mid, "method": method, "params": params or {}, **({"sessionId": session} if session else {})}
        self.out.write(json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        with self.cv:
            while mid not in self.replies:
                if time.monotonic() > deadline or self.proc.poll() is not None:
                    raise TimeoutError(f"Chromium did not answer {method}")
                self.cv.wait(0.5)
            reply = self.replies.pop(mid)
        if "error" in reply:
            raise RuntimeError(f"{method}: {reply['error']}")
        return reply["result"]

    def wait_for(self, method: str, since: int, session: str | None = None, timeout: float = 60) -> dict:
        deadline = time.monotonic() + timeout
        with self.cv:
            while True:
                for event in self.events[since:]:
                    if event["method"] == method and (session is None or event.get("sessionId") == session):
                        return event
                if time.monotonic() > deadline:
                    raise TimeoutError(f"no {method} from Chromium")
                self.cv.wait(0.5)

    def page(self) -> "Page":
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        return Page(self, session)

    def __enter__(self) -> "Chromium":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        try:
            self.call("Browser.close", timeout=10)
        except Exception:
            pass
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


class Page:
    """One tab: navigate, evaluate, press keys, take screenshots, and what it logged or asked the network for."""

    def __init__(self, browser: Chromium, session: str):
        self.browser, self.session = browser, session
        self.start = len(browser.events)
        for domain in ("Runtime", "Log", "Page", "Network"):
            self.call(f"{domain}.enable")
        width, height = browser.size
        self.call("Emulation.setDeviceMetricsOverride", {"width": width, "height": height, "deviceScaleFactor": 1,
                                                         "mobile": False})

    def call(self, method: str, params: dict | None = None, timeout: float = 60) -> dict:
        return self.browser.call(method, params, self.session, timeout)

    def viewport(self, width: int, height: int, scale: float = 1.0) -> None:
        """Show the page as a screen of ``width`` × ``height`` CSS pixels, ``scale`` device pixels to each."""
        self.call("Emulation.setDeviceMetricsOverride", {"width": width, "height": height,
                                                         "deviceScaleFactor": scale, "mobile": False})

    def open(self, url: str) -> None:
        since = len(self.browser.events)
        self.call("Page.navigate", {"url": url})
        self.browser.wait_for("Page.loadEventFired", since, self.session)
        self.eval("new Promise((done, fail) => { const t0 = Date.now(); (function wait() {"
                  " if (window.cs451Deck && cs451Deck.ready) done(true);"
                  " else if (Date.now() - t0 > 30000) fail(new Error('reveal.js never became ready'));"
                  " else setTimeout(wait, 20); })(); })")

    def eval(self, expression: str):
        result = self.call("Runtime.evaluate", {"expression": expression, "awaitPromise": True, "returnByValue": True})
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression[:80]}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def key(self, key: str, code: int) -> None:
        for kind in ("keyDown", "keyUp"):
            self.call("Input.dispatchKeyEvent", {"type": kind, "key": key, "code": key, "windowsVirtualKeyCode": code})

    def screenshot(self) -> "Image.Image":
        from PIL import Image
        data = self.call("Page.captureScreenshot", {"format": "png"})["data"]
        return Image.open(io.BytesIO(base64.b64decode(data))).convert("RGB")

    def problems(self) -> list[str]:
        """Console errors, uncaught exceptions and every request for anything but data: and file: URLs."""
        found = []
        for event in self.browser.events[self.start:]:
            if event.get("sessionId") != self.session:
                continue
            method, params = event["method"], event["params"]
            if method == "Runtime.exceptionThrown":
                found.append(f"exception: {params['exceptionDetails'].get('exception', {}).get('description')}")
            elif method == "Runtime.consoleAPICalled" and params["type"] in ("error", "assert"):
                found.append("console: " + " ".join(str(a.get("value", a.get("description"))) for a in params["args"]))
            elif method == "Log.entryAdded" and params["entry"]["level"] == "error":
                found.append(f"log: {params['entry']['text']} {params['entry'].get('url', '')}")
            elif method == "Network.requestWillBeSent":
                url = params["request"]["url"]
                if not url.startswith(("data:", "file:", "about:")):
                    found.append(f"network: {url[:120]}")
        return found
