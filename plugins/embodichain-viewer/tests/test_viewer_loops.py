"""Every loop of the project opens the viewer when asked: the seed tutorial run without
``--headless``, ``run-env --viewer``, ``eval-policy --viewer`` and ``train-rl --play --viewer``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from embodichain_core.cli.main import main as embodichain

URL_LINE = "[embodichain] viewer: http://localhost:"


def _no_display() -> dict:
    return {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}


@pytest.mark.slow  # ~45 s: the tutorial's episode of 100 steps with its stereo camera
def test_seed_tutorial_without_headless_opens_the_browser_viewer() -> None:
    cmd = [sys.executable, "-m", "embodichain_tasks.tutorials.modular_env", "--num_envs", "1", "--max_episodes", "1"]
    out = subprocess.run(cmd, env=_no_display(), capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-2000:]
    assert URL_LINE in out.stdout


def test_run_env_viewer_flag(capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert embodichain(["run-env", "--viewer", "auto", "--max_episodes", "1", "--max_steps", "5", "--quiet"]) == 0
    assert URL_LINE in capsys.readouterr().out
    code = embodichain(["run-env", "--viewer", "native", "--max_episodes", "1", "--quiet"])
    assert code == 2
    assert "use --viewer browser" in capsys.readouterr().err


def test_eval_policy_viewer_turns_headless_off() -> None:
    from embodichain_lerobot.eval_cli import _plan, build_parser

    args = build_parser().parse_args(
        ["--policy", "unused", "--task", "EmbodiChainDemo-v0", "--episodes", "1", "--viewer", "browser"]
    )
    plan = _plan(args)
    assert (plan.cfg.sim_cfg.headless, plan.cfg.sim_cfg.viewer) == (False, "browser")
    headless = _plan(
        build_parser().parse_args(["--policy", "unused", "--task", "EmbodiChainDemo-v0", "--episodes", "1"])
    )
    assert headless.cfg.sim_cfg.headless is True


def test_train_rl_play_with_the_viewer(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "rl"
    train = ["train-rl", "--task", "PushCube-v1", "--num_envs", "4", "--steps", "150", "--max_episode_steps", "8"]
    assert embodichain([*train, "--out", str(out)]) == 0
    capsys.readouterr()
    video = tmp_path / "play.mp4"
    assert (
        embodichain(["train-rl", "--play", str(out / "model_1.pt"), "--video", str(video), "--viewer", "browser"]) == 0
    )
    assert URL_LINE in capsys.readouterr().out
    assert video.is_file()
