"""``embodichain run-env`` data generation with ``LeRobotRecorder`` from a gym config:
scripted demonstrations are recorded, failed attempts are discarded, and the
summary prints the dataset path."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import torch

from lerobot_helpers import load, seven_dof_arm_mjcf

from embodichain_core.cli import run_env
from embodichain_core.envs import EmbodiedEnv


class DemoPush(EmbodiedEnv):
    """A 4-step scripted demo; the first attempt fails, every later one succeeds at its last step."""

    def create_demo_action_list(self) -> list:
        self.attempts = getattr(self, "attempts", 0) + 1
        return [torch.full(self.action_space.shape, 0.05 * k) for k in range(4)]

    def compute_task_state(self, **kwargs: Any) -> tuple:
        success = (self.elapsed_steps >= 4) & (getattr(self, "attempts", 0) >= 2)
        return success, torch.zeros_like(success), {}


def write_config(path: Path, task: str, save_path: Path, func: str) -> Path:
    dataset = {
        "lerobot": {
            "func": func,
            "params": {
                "save_path": str(save_path),
                "robot_meta": {"robot_type": "arm7"},
                "instruction": {"lang": "reach forward"},
                "extra": {"scene_type": "empty", "task_description": "reach"},
            },
        }
    }
    data = {
        "id": task,
        "num_envs": 2,
        "max_episode_steps": 10,
        "max_episodes": 4,
        "demo_max_attempts": 3,
        "env": {"seed": 0, "verbose": False, "control_parts": ["arm"], "dataset": dataset},
        "robot": {"uid": "arm", "mjcf": seven_dof_arm_mjcf(), "control_parts": {"arm": ["joint[1-7]"]}},
    }
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("func", ["LeRobotRecorder", "AsyncLeRobotRecorder"])
def test_data_generation_records_the_successful_demos(
    tmp_path: Path, task_id: str, func: str, capsys: pytest.CaptureFixture
) -> None:
    config = write_config(tmp_path / "gen.json", task_id, tmp_path / "data", func)
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    out = capsys.readouterr().out
    path = tmp_path / "data" / "arm7_empty_reach_000"
    assert f"data         {path}" in out
    assert "discarded    2 failed demo episode(s)" in out
    ds = load(path)
    assert ds.num_episodes == 4
    assert [int(x) for x in ds.meta.episodes["length"]] == [4, 4, 4, 4]
    assert {ds[i]["task"] for i in range(len(ds))} == {"reach forward"}
    assert float(ds[3]["action"][0]) == pytest.approx(0.15)
