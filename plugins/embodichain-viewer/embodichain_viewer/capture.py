"""Screenshots of the viewers without a desktop: a private Xvfb display for the native
window, headless Chromium for the browser page (Debian packages ``xvfb`` and ``chromium``).

Used by the viewer tests and by ``scripts/screenshots.py`` (the images of docs/viewer.md).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Optional

import numpy as np

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


def chromium() -> Optional[str]:
    """The system Chromium's path, or ``None``."""
    return next((p for p in map(shutil.which, CHROMIUM_NAMES) if p), None)


def browser_screenshot(url: str, path: Path, size: tuple[int, int] = (1280, 800), wait_s: float = 12.0) -> Path:
    """Open ``url`` in headless Chromium (software WebGL), let it run ``wait_s`` seconds of
    real time (the page connects to the viewer and draws), then save a PNG of it.

    The capture goes through the DevTools protocol (``Page.captureScreenshot``), since
    Chromium's own ``--screenshot`` fires before the page's websocket has delivered the scene.

    Raises:
        RuntimeError: no Chromium, or no page to capture.
    """
    exe = chromium()
    if exe is None:
        raise RuntimeError("no chromium found (apt-get install chromium)")
    with tempfile.TemporaryDirectory(prefix="embodichain-chromium-") as profile:
        cmd = [
            exe,
            "--headless",
            "--no-sandbox",
            "--enable-unsafe-swiftshader",
            "--use-angle=swiftshader",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
            f"--user-data-dir={profile}",
            f"--window-size={size[0]},{size[1]}",
            url,
        ]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            png = _devtools_capture(Path(profile), wait_s)
        finally:
            proc.terminate()
            proc.wait(timeout=20)
    Path(path).write_bytes(png)
    return Path(path)


def _devtools_capture(profile: Path, wait_s: float) -> bytes:
    """PNG bytes of the first page of the Chromium whose profile is ``profile``."""
    import base64
    import json
    import urllib.request

    from websockets.sync.client import connect

    port_file = profile / "DevToolsActivePort"
    end = time.monotonic() + 30
    while not port_file.is_file() or not port_file.read_text().strip():
        if time.monotonic() > end:
            raise RuntimeError("chromium opened no DevTools port")
        time.sleep(0.1)
    port = int(port_file.read_text().split()[0])
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as answer:
        pages = [t for t in json.load(answer) if t.get("type") == "page"]
    if not pages:
        raise RuntimeError("chromium shows no page")
    time.sleep(wait_s)
    with connect(pages[0]["webSocketDebuggerUrl"], max_size=None) as ws:
        ws.send(json.dumps({"id": 1, "method": "Page.captureScreenshot", "params": {"format": "png"}}))
        while True:
            reply = json.loads(ws.recv(timeout=60))
            if reply.get("id") == 1:
                return base64.b64decode(reply["result"]["data"])


class Xvfb:
    """A private virtual X display (``with Xvfb() as display: ...``; ``display`` like ``":5"``)."""

    def __init__(self, size: tuple[int, int] = (1280, 800)):
        self.size = size
        self.display = ""
        self._proc: Optional[subprocess.Popen] = None

    def __enter__(self) -> str:
        exe = shutil.which("Xvfb")
        if exe is None:
            raise RuntimeError("no Xvfb found (apt-get install xvfb)")
        read, write = os.pipe()
        screen = f"{self.size[0]}x{self.size[1]}x24"
        self._proc = subprocess.Popen(
            [exe, "-displayfd", str(write), "-screen", "0", screen, "-nolisten", "tcp"],
            pass_fds=(write,),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(write)
        with os.fdopen(read) as pipe:
            number = pipe.readline().strip()
        if not number:
            self.__exit__()
            raise RuntimeError("Xvfb did not start")
        self.display = f":{number}"
        return self.display

    def __exit__(self, *exc: object) -> None:
        if self._proc is not None:
            self._proc.terminate()
            self._proc.wait(timeout=10)
            self._proc = None


def x_screenshot(display: str, path: Path) -> Path:
    """Save a PNG of X display ``display`` (Pillow's X11 grab)."""
    from PIL import ImageGrab

    ImageGrab.grab(xdisplay=display).save(path)
    return Path(path)


def is_blank(path: Path, min_std: float = 4.0) -> bool:
    """Whether the image is (nearly) one flat colour."""
    from PIL import Image

    return float(np.asarray(Image.open(path).convert("L"), dtype=np.float64).std()) < min_std


def changed_fraction(a: Path, b: Path, threshold: int = 12) -> float:
    """The fraction of pixels whose grey level differs by more than ``threshold`` between two PNGs."""
    from PIL import Image

    ga = np.asarray(Image.open(a).convert("L"), dtype=np.int16)
    gb = np.asarray(Image.open(b).convert("L"), dtype=np.int16)
    return float((np.abs(ga - gb) > threshold).mean())
