"""LeRobotRecorder through the env loop, read back with ``LeRobotDataset``: values,
shapes, episode lengths, task strings (num_envs 1 and 3), episode selection,
folder naming, fps, finalize."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from lerobot_helpers import (
    JOINTS,
    TASK,
    arm_cfg,
    as_np,
    datasets_under,
    episode_items,
    expected_episodes,
    load,
    recorder_cfg,
    reset,
    run_script,
)

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import ActionTerm, ActionTermCfg, ObservationCfg

SCRIPT_1 = [["."], ["."], ["."], ["s"], ["."], ["f"], ["."], ["."], ["s"], ["."], ["."]]
SCRIPT_3 = [
    [".", ".", "."],
    [".", "s", "."],
    ["s", ".", "."],
    [".", ".", "f"],
    [".", ".", "."],
    [".", "s", "s"],
    ["f", ".", "."],
    [".", ".", "."],
    ["s", ".", "."],
    [".", ".", "s"],
    [".", ".", "."],
]


def record(make_env: Any, tmp_path: Path, script: list, num_envs: int, **kw: Any) -> tuple[Any, list, str]:
    env = make_env(arm_cfg(num_envs, dataset=recorder_cfg(tmp_path, **kw)))
    log: list = []
    reset(env)
    run_script(env, script, log)
    env.close()
    (path,) = env.dataset_manager.finalize()
    return env, log, path


@pytest.mark.parametrize("num_envs, script", [(1, SCRIPT_1), (3, SCRIPT_3)])
def test_round_trip_through_lerobot_dataset(make_env: Any, tmp_path: Path, num_envs: int, script: list) -> None:
    env, log, path = record(make_env, tmp_path, script, num_envs)
    expected = expected_episodes(script, log, num_envs)
    assert Path(path).name == "arm7_table_top_push_the_cube_000"
    ds = load(path)
    assert ds.num_episodes == len(expected)
    assert ds.fps == 25
    assert ds.meta.robot_type == "Arm7"
    assert [int(x) for x in ds.meta.episodes["length"]] == [len(rows) for _, rows in expected]
    assert len(ds) == sum(len(rows) for _, rows in expected)
    assert ds.features["observation.state"]["names"] == JOINTS
    assert ds.features["action"]["shape"] == (7,)
    assert ds.features["action"]["names"] == JOINTS
    for e, (env_id, rows) in enumerate(expected):
        items = episode_items(ds, e)
        for t, (item, (obs, action)) in enumerate(zip(items, rows)):
            assert item["task"] == TASK
            assert item["subtask"] == TASK
            assert int(item["frame_index"]) == t
            assert float(item["timestamp"]) == pytest.approx(t / 25)
            np.testing.assert_array_equal(as_np(item["observation.state"]), obs["robot"]["qpos"])
            np.testing.assert_array_equal(as_np(item["observation.qvel"]), obs["robot"]["qvel"])
            np.testing.assert_array_equal(as_np(item["observation.qf"]), obs["robot"]["qf"])
            np.testing.assert_array_equal(as_np(item["action"]), action)
            assert int(item["annotation.episode_step"]) == t
            assert int(item["annotation.segment_end"]) == (t == len(rows) - 1)
        assert bool(items[-1]["next.done"])
        assert bool(items[-1]["next.success"])
        assert int(items[-1]["annotation.terminated"]) == 1
        assert not bool(items[0]["next.done"])
    sidecar = [json.loads(x) for x in (Path(path) / "meta/embodichain_episodes.jsonl").read_text().splitlines()]
    assert [r["env_id"] for r in sidecar] == [i for i, _ in expected]
    assert [r["lerobot_episode_index"] for r in sidecar] == list(range(len(expected)))
    assert sidecar[0]["total_time"] == pytest.approx(len(expected[0][1]) * env.step_dt)
    assert sidecar[0]["extra"] == {"scene_type": "Table Top"}
    assert sidecar[0]["schema_version"] == 2
    assert not (Path(path) / ".embodichain_staging").exists()


def test_save_failed_episodes_keeps_failures(make_env: Any, tmp_path: Path) -> None:
    _, _, path = record(make_env, tmp_path, SCRIPT_1, 1, save_failed=True)
    ds = load(path)
    assert [int(x) for x in ds.meta.episodes["length"]] == [4, 2, 3]
    assert [bool(ds[i]["next.success"]) for i in (3, 5)] == [True, False]


def test_discarding_reset_and_partial_episodes_are_not_saved(make_env: Any, tmp_path: Path) -> None:
    env = make_env(arm_cfg(2, dataset=recorder_cfg(tmp_path)))
    reset(env)
    run_script(env, [[".", "."]] * 3)
    env.success_flags[:] = True
    env.reset(options={"save_data": False})  # successful, but discarded
    env.success_flags[:] = False
    run_script(env, [[".", "."], ["s", "."], [".", "."]])  # env 0: 2 frames; env 1: live at close
    rec = env.dataset_manager.get_functor("rec")
    assert rec.saved_episodes == 1
    assert rec.live_length(1) == 3
    assert rec.discarded_episodes == 2
    env.close()
    ds = load(env.dataset_manager.finalize()[0])
    assert ds.num_episodes == 1
    assert len(ds) == 2


def test_finalize_is_idempotent_and_empty_runs_leave_nothing(make_env: Any, tmp_path: Path) -> None:
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    reset(env)
    run_script(env, [["."]] * 3)
    rec = env.dataset_manager.get_functor("rec")
    assert rec.finalize() is None
    assert rec.finalize() is None
    assert list(Path(tmp_path).iterdir()) == []
    with pytest.raises(RuntimeError, match="finalized"):
        rec(env, torch.tensor([0]))
    env2 = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    reset(env2)
    run_script(env2, [["."], ["s"], ["."]])
    rec2 = env2.dataset_manager.get_functor("rec")
    first = rec2.finalize()
    assert first is not None
    assert rec2.finalize() == first
    env2.close()
    assert env2.dataset_manager.finalize() == [first]
    assert load(first).num_episodes == 1


def test_folder_numbers_increase_and_never_overwrite(make_env: Any, tmp_path: Path) -> None:
    (tmp_path / "arm7_table_top_push_the_cube_004").mkdir()
    (tmp_path / "arm7_table_top_push_the_cube_004" / "keep.txt").write_text("mine")
    paths = [record(make_env, tmp_path, [["s"]], 1)[2] for _ in range(2)]
    assert [Path(p).name for p in paths] == ["arm7_table_top_push_the_cube_005", "arm7_table_top_push_the_cube_006"]
    assert (tmp_path / "arm7_table_top_push_the_cube_004" / "keep.txt").read_text() == "mine"
    assert len(datasets_under(tmp_path)) == 3


def test_non_integer_control_frequency_is_a_clear_error(make_env: Any, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"integer fps.*33\.33"):
        make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path), sim_steps_per_control=3))
    assert list(tmp_path.iterdir()) == []


def test_misspelled_param_names_the_functor(make_env: Any, tmp_path: Path) -> None:
    cfg = recorder_cfg(tmp_path)
    cfg["rec"].params["use_video"] = True
    with pytest.raises(ConfigError, match=r"env\.dataset\.rec\.params\.use_video.*Did you mean 'use_videos'"):
        make_env(arm_cfg(1, dataset=cfg))


def _row_ids(env: Any, obs: Any) -> torch.Tensor:
    return torch.arange(env.num_envs, dtype=torch.float32) * 10 + env.elapsed_steps.float()


def _cube_pose(env: Any, obs: Any) -> torch.Tensor:
    return env.scene["cube"].get_local_pose()


def test_extra_observations_and_dict_actions_are_recorded(make_env: Any, tmp_path: Path) -> None:
    observations = {
        "tag": ObservationCfg(func=_row_ids, mode="add", name="row_tag"),
        "pose": ObservationCfg(func=_cube_pose, mode="add", name="object/cube/pose"),
    }
    env = make_env(arm_cfg(2, dataset=recorder_cfg(tmp_path), observations=observations))
    reset(env)
    for t in range(3):
        env.success_flags[:] = t == 2
        env.step({"qpos": torch.full((2, 7), 0.1 * t)})
    env.close()
    ds = load(env.dataset_manager.finalize()[0])
    assert ds.features["row_tag"]["shape"] == (1,)
    assert ds.features["observation.object.cube.pose"]["shape"] == (7,)
    assert [float(ds[i]["row_tag"]) for i in range(6)] == [0, 1, 2, 10, 11, 12]
    np.testing.assert_allclose(as_np(ds[2]["action"]), np.full(7, 0.2, np.float32))


class OffsetQpos(ActionTerm):
    """qpos = action + 0.1, its values named by the term (not the joints)."""

    def action_names(self) -> list[str]:
        return [f"offset_{i}" for i in range(self.action_dim)]

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return action + 0.1


def test_the_action_columns_take_the_action_terms_names(make_env: Any, tmp_path: Path) -> None:
    """An action term's values are not joint targets: the recorded names are the term's."""
    actions = {"offset": ActionTermCfg(func=OffsetQpos)}
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path), actions=actions))
    reset(env)
    for t in range(3):
        env.success_flags[:] = t == 2
        env.step(torch.zeros(1, 7))
    env.close()
    ds = load(env.dataset_manager.finalize()[0])
    assert ds.features["action"]["names"] == [f"offset_{i}" for i in range(7)]
