"""``observation.environment_state``: the mapping's pieces; the IL pipeline's config; merged env descriptions."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_lerobot.config import parse_params
from embodichain_lerobot.env_state import ENV_STATE, keys_from_names, state_keys_of, state_source, trained_state_keys
from embodichain_lerobot.features import Source
from embodichain_lerobot.il_pipeline import MAIN_JOB
from embodichain_lerobot.il_recipes import pipeline_config


def _sources() -> list[Source]:
    return [
        Source("robot/qpos", "observation.state", "numeric", "float32", (2,)),
        Source("fork_pose", "fork_pose", "numeric", "float32", (4, 4)),
        Source("opening", "opening", "numeric", "float32", (1,)),
        Source("sensor/cam/color", "observation.images.cam", "image", "uint8", (4, 4, 3)),
    ]


def test_listed_observations_become_one_named_vector_in_the_listed_order() -> None:
    sources, state = state_source(_sources(), ["opening", "fork_pose"])
    assert state is not None
    assert [s.name for s in sources] == ["observation.state", "observation.images.cam", ENV_STATE]
    assert state.shape == (17,)
    assert state.names[:3] == ["opening", "fork_pose[0,0]", "fork_pose[0,1]"]
    flat = {"opening": np.array([[0.5], [0.25]]), "fork_pose": np.arange(32.0).reshape(2, 4, 4)}
    values = state.take(flat, 2)
    assert values.dtype == np.float32
    np.testing.assert_array_equal(values[1], np.concatenate([[0.25], np.arange(16.0, 32.0)]))
    assert keys_from_names(state.names) == ["opening", "fork_pose"]


def test_a_wrong_key_names_the_closest_and_a_camera_is_refused() -> None:
    with pytest.raises(ConfigError, match="no 'fork_pos'.*Did you mean 'fork_pose'"):
        state_source(_sources(), ["fork_pos"])
    with pytest.raises(ConfigError, match="camera stream"):
        state_source(_sources(), ["sensor/cam/color"])
    with pytest.raises(ConfigError, match="environment_state"):
        parse_params({"environment_state": "fork_pose"})  # a string, not a list


def test_the_keys_come_from_the_recorder_or_from_the_training_dataset(tmp_path: Path) -> None:
    section = {"rec": {"func": "LeRobotRecorder", "params": {"environment_state": ["fork_pose"]}}}
    assert state_keys_of(section) == ["fork_pose"]
    assert state_keys_of(None) == []
    data = tmp_path / "demos"
    (data / "meta").mkdir(parents=True)
    names = ["opening", "fork_pose[0,0]", "fork_pose[3,3]"]
    (data / "meta" / "info.json").write_text(json.dumps({"features": {ENV_STATE: {"names": names}}}))
    policy = tmp_path / "pretrained_model"
    policy.mkdir()
    assert trained_state_keys(policy) == []  # no train_config.json
    (policy / "train_config.json").write_text(json.dumps({"dataset": {"root": str(data)}}))
    assert trained_state_keys(policy) == ["opening", "fork_pose"]


def test_the_state_recipe_drops_the_cameras_and_needs_environment_state(tmp_path: Path) -> None:
    data = pipeline_config(MAIN_JOB, "state")
    assert data["sensor"] == []
    assert data["env"]["dataset"]["lerobot"]["params"]["use_videos"] is False
    assert data["env"]["dataset"]["lerobot"]["params"]["environment_state"] == ["fork_pose"]
    plain = json.loads(MAIN_JOB.read_text())
    del plain["env"]["dataset"]["lerobot"]["params"]["environment_state"]
    (tmp_path / "c.json").write_text(json.dumps(plain))
    with pytest.raises(ValueError, match="environment_state"):
        pipeline_config(tmp_path / "c.json", "state")


def test_merged_shards_keep_one_env_description(tmp_path: Path) -> None:
    from embodichain_lerobot.env_meta import ENV_META, merge_env_meta, read_env_meta

    meta = {"task_id": "PickFork-v1", "cfg_class": "m:Cfg", "env_cfg": {}, "versions": {"mujoco": "4.0.0"}}
    shards = [tmp_path / "s0", tmp_path / "s1"]
    for shard in shards:
        (shard / "meta").mkdir(parents=True)
        (shard / ENV_META).write_text(json.dumps(meta))
    assert merge_env_meta(shards, tmp_path / "a") is not None
    assert read_env_meta(tmp_path / "a")["merged_from"] == 2
    (shards[1] / ENV_META).write_text(json.dumps({**meta, "versions": {"mujoco": "3.3.0"}}))
    with pytest.warns(UserWarning, match="different versions"):
        merge_env_meta(shards, tmp_path / "b")
    assert len(read_env_meta(tmp_path / "b")["shard_versions"]) == 2
    (shards[1] / ENV_META).write_text(json.dumps({**meta, "task_id": "OpenDrawer-v1"}))
    with pytest.raises(ValueError, match="disagree on task_id"):
        merge_env_meta(shards, tmp_path / "c")
    assert merge_env_meta([tmp_path / "none"], tmp_path / "d") is None
