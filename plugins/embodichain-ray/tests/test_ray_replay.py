"""A dataset merged by ``embodichain generate`` from two workers carries its env description
and replays exactly (``embodichain dataset replay``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from embodichain_ray import cli

from embodichain_lerobot import cli as dataset_cli
from embodichain_lerobot.env_meta import ENV_META


@pytest.mark.slow  # Ray's start and two workers: ~40 s
def test_a_merged_dataset_replays_every_episode_exactly(tmp_path: Path, tiny_config: Any, capsys: Any) -> None:
    out = tmp_path / "merged"
    argv = ["--gym_config", tiny_config(), "--episodes", "4", "--workers", "2", "--seed", "5"]
    assert cli.main([*argv, "--output", str(out), "--quiet"]) == 0
    meta = json.loads((out / ENV_META).read_text())
    assert meta["task_id"] == "PickFork-v1"
    assert meta["merged_from"] == 2
    capsys.readouterr()
    report = tmp_path / "replay.json"
    assert dataset_cli.main(["replay", str(out), "--all", "--json", str(report)]) == 0, capsys.readouterr().out
    data = json.loads(report.read_text())
    assert len(data["episodes"]) == 4
    assert all(max(e["max_error"].values()) == 0.0 for e in data["episodes"])
