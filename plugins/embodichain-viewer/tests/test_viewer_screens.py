"""The viewers really open and draw the scene: MuJoCo's native window under Xvfb and the
browser page in headless Chromium, each photographed in two distinct env states (slow)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import torch
from viewer_helpers import demo_env, free_port, wait_for

from embodichain_viewer.capture import Xvfb, browser_screenshot, changed_fraction, chromium, is_blank

HERE = Path(__file__).resolve().parent
pytestmark = pytest.mark.slow


def _swing(env: object, frac: float, steps: int = 40) -> None:
    space = env.unwrapped.single_action_space  # type: ignore[attr-defined]
    target = torch.as_tensor(space.low + frac * (space.high - space.low)).expand(env.unwrapped.num_envs, -1)  # type: ignore[attr-defined]
    for _ in range(steps):
        env.step(target.clone())  # type: ignore[attr-defined]


@pytest.mark.skipif(shutil.which("Xvfb") is None, reason="needs Xvfb (apt-get install xvfb)")
def test_native_window_under_xvfb_shows_the_scene_move(tmp_path: Path) -> None:
    with Xvfb() as display:
        env = {
            **os.environ,
            "DISPLAY": display,
            "PYTHONPATH": os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")]),
        }
        env.pop("WAYLAND_DISPLAY", None)
        out = subprocess.run(
            [sys.executable, str(HERE / "native_child.py"), str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            timeout=180,
        )
    assert out.returncode == 0, out.stderr[-2000:]
    a, b = tmp_path / "native_a.png", tmp_path / "native_b.png"
    assert not is_blank(a)
    assert not is_blank(b)
    assert changed_fraction(a, b) > 0.002  # the arm is drawn in another pose (the overlay text alone: < 0.001)


@pytest.mark.skipif(chromium() is None, reason="needs Chromium (apt-get install chromium)")
def test_browser_page_in_headless_chromium_shows_the_scene_move(tmp_path: Path, every_step_published: None) -> None:
    env = demo_env("browser", free_port())
    try:
        viewer = env.unwrapped._viewer.viewer
        shots = []
        env.reset(seed=0)
        for name, frac in (("a", 0.15), ("b", 0.85)):
            _swing(env, frac)
            wait_for(lambda: viewer.last is not None and viewer.last.step == env.unwrapped._viewer.steps, "the step")
            shots.append(browser_screenshot(viewer.url, tmp_path / f"browser_{name}.png"))
    finally:
        env.close()
    assert not is_blank(shots[0])
    assert not is_blank(shots[1])
    assert changed_fraction(*shots) > 0.001  # measured 0.0055; a viewer that never poses the bodies: 0.0001
