"""The screenshots of docs/viewer.md: both viewers on the seed tutorial's scene and on PushCube-v1.

Needs Xvfb and Chromium (scripts/setup_env.sh installs them). Each scene runs a few
steps of zero actions, then the browser page is photographed in headless Chromium and the
native window on a private Xvfb display (in a child process that gets the display).

    $ .venv/bin/python plugins/embodichain-viewer/scripts/screenshots.py --out docs/images
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

TARGETS = {
    "tutorial": "plugins/embodichain-tasks/embodichain_tasks/configs/modular_env.json",
    "push_cube": "PushCube-v1",
}


def _env(target: str, viewer: str) -> object:
    from embodichain_core.cli.run_env import build_parser, make_env, prepare

    args = build_parser().parse_args([target, "--viewer", viewer, "--num_envs", "2", "--quiet"])
    return make_env(prepare(args))


def _run_until_drawn(env: object, steps: int = 30) -> object:
    import torch

    base = env.unwrapped  # type: ignore[attr-defined]
    env.reset(seed=0)  # type: ignore[attr-defined]
    for _ in range(steps):
        obs, reward, _, _, info = env.step(torch.zeros(base.action_space.shape))  # type: ignore[attr-defined]
    viewer = base._viewer.viewer
    base._viewer.slot.put(base._viewer.snapshot(obs, reward, info))  # the last step, whatever the throttle
    end = time.monotonic() + 30
    while viewer.last is None or viewer.last.step != base._viewer.steps:
        if time.monotonic() > end:
            raise RuntimeError("the viewer drew nothing in 30 s")
        time.sleep(0.05)
    return viewer


def browser_shot(name: str, target: str, out: Path) -> Path:
    """Photograph the browser viewer of ``target`` into ``out/viewer_browser_<name>.png``."""
    from embodichain_viewer.capture import browser_screenshot

    env = _env(target, "browser")
    try:
        viewer = _run_until_drawn(env)
        return browser_screenshot(viewer.url, out / f"viewer_browser_{name}.png")  # type: ignore[attr-defined]
    finally:
        env.close()  # type: ignore[attr-defined]


def native_shot(name: str, target: str, out: Path) -> Path:
    """Photograph the native window of ``target`` (run with ``DISPLAY`` set), cropped to it."""
    from PIL import ImageGrab

    env = _env(target, "native")
    try:
        _run_until_drawn(env)
        time.sleep(1.0)  # the window's thread renders the synced state
        image = ImageGrab.grab(xdisplay=os.environ["DISPLAY"])
    finally:
        env.close()  # type: ignore[attr-defined]
    ys, xs = np.nonzero(np.asarray(image.convert("L")))
    path = out / f"viewer_native_{name}.png"
    image.crop((int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)).save(path)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/images", help="folder of the PNGs (default docs/images)")
    parser.add_argument("--native", metavar="NAME", help=argparse.SUPPRESS)  # the child under Xvfb
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.native:
        print(native_shot(args.native, TARGETS[args.native], out))
        return 0
    from embodichain_viewer.capture import Xvfb

    for name, target in TARGETS.items():
        print(browser_shot(name, target, out))
        with Xvfb(size=(1600, 1000)) as display:
            env = {**os.environ, "DISPLAY": display}
            env.pop("WAYLAND_DISPLAY", None)
            subprocess.run([sys.executable, __file__, "--out", str(out), "--native", name], env=env, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
