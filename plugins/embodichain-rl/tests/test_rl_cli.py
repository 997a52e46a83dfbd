"""``embodichain train-rl``: registered through the commands hook; a tiny training with
each library writes checkpoints, a curve and tensorboard events; ``--play`` writes an mp4;
``evaluate`` runs the checkpoint's policy."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import imageio.v2 as imageio
import pytest

from embodichain_core.cli.main import main as embodichain
from embodichain_rl.evaluate import evaluate


def test_the_command_is_registered() -> None:
    from embodichain_core.plugins import get_registry, load_plugins

    load_plugins()
    assert get_registry("commands").find("train-rl").target == "embodichain_rl.cli:main"


def test_loading_the_plugin_imports_no_rl_library() -> None:
    code = (
        "import sys, embodichain_rl\n"
        "from embodichain_core.plugins import load_plugins; load_plugins()\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'rsl_rl', 'stable_baselines3', 'tensordict'}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


@pytest.mark.parametrize("library, checkpoint, events", [("rsl_rl", "model_1.pt", "."), ("sb3", "model.zip", "tb")])
def test_train_then_play(tmp_path: Path, library: str, checkpoint: str, events: str) -> None:
    out = tmp_path / library
    args = [
        "train-rl",
        "--task",
        "PushCube-v1",
        "--library",
        library,
        "--num_envs",
        "4",
        "--steps",
        "150",
        "--max_episode_steps",
        "8",
        "--out",
        str(out),
    ]
    assert embodichain(args) == 0
    assert (out / checkpoint).is_file()
    assert list((out / events).rglob("events.out.tfevents.*"))
    meta = json.loads((out / "embodichain_rl.json").read_text())
    assert meta["library"] == library
    assert meta["task"] == "PushCube-v1"
    assert meta["max_episode_steps"] == 8
    with (out / "curve.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert rows
    assert any(r["episodes"] not in ("", "0") for r in rows)
    video = tmp_path / f"{library}.mp4"
    assert embodichain(["train-rl", "--play", str(out / checkpoint), "--video", str(video)]) == 0
    frames = [frame for frame in imageio.get_reader(str(video), format="FFMPEG")]  # its len() is inf
    for deterministic in (True, False):
        result = evaluate(out / checkpoint, num_envs=3, deterministic=deterministic)
        assert result["episodes"] == 3
        assert 0.0 <= result["success_rate"] <= 1.0
        assert result["mean_return"] > 0
    assert len(frames) == 9
    assert frames[0].shape == (240, 320, 3)
    assert frames[0].std() > 5


def test_bad_arguments(tmp_path: Path) -> None:
    assert embodichain(["train-rl", "--num_envs", "0"]) == 2
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        embodichain(["train-rl", "--play", str(tmp_path / "missing.pt")])
    with pytest.raises(ValueError, match="unknown task 'Nope-v0'"):
        embodichain(["train-rl", "--task", "Nope-v0", "--steps", "1", "--out", str(tmp_path / "nope")])
    (tmp_path / "model.pt").write_bytes(b"")
    with pytest.raises(FileNotFoundError, match="embodichain_rl.json"):
        embodichain(["train-rl", "--play", str(tmp_path / "model.pt")])
