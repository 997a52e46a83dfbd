"""The observation layout: sorted leaf paths, images apart, a stable round trip, clear errors."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch

from embodichain_rl.flatten import ObsFlattener, leaf

SPACE = gym.spaces.Dict(
    {
        "robot": gym.spaces.Dict({"qvel": gym.spaces.Box(-1, 1, (2,)), "qpos": gym.spaces.Box(-1, 1, (2,))}),
        "cube_pose": gym.spaces.Box(-1, 1, (7,)),
        "sensor": gym.spaces.Dict({"cam": gym.spaces.Dict({"color": gym.spaces.Box(0, 255, (4, 5, 3), np.uint8)})}),
        "grid": gym.spaces.Box(-1, 1, (2, 3)),
    }
)


def batch(n: int) -> dict:
    return {
        "robot": {"qvel": torch.full((n, 2), 2.0), "qpos": torch.full((n, 2), 1.0)},
        "cube_pose": torch.arange(7.0).expand(n, 7),
        "grid": torch.zeros(n, 2, 3),
        "sensor": {"cam": {"color": torch.zeros(n, 4, 5, 3, dtype=torch.uint8)}},
    }


def test_layout_is_sorted_and_keeps_images_apart() -> None:
    flat = ObsFlattener.from_space(SPACE)
    assert flat.state_paths == ["cube_pose", "grid", "robot/qpos", "robot/qvel"]
    assert flat.state_sizes == [7, 6, 2, 2]
    assert flat.state_dim == 17
    assert flat.image_paths == ["sensor/cam/color"]
    assert flat.image_shapes == [(4, 5, 3)]
    state = flat.state(batch(3))
    assert state.shape == (3, 17)
    assert state.dtype == torch.float32
    assert state[0, :7].tolist() == list(range(7))
    assert state[0, 13:].tolist() == [1.0, 1.0, 2.0, 2.0]
    assert flat.images(batch(3))["sensor/cam/color"].shape == (3, 4, 5, 3)


def test_skip_round_trip_and_errors() -> None:
    flat = ObsFlattener.from_space(SPACE, skip=("sensor",))
    assert flat.image_paths == []
    assert ObsFlattener.from_dict(flat.to_dict()) == flat
    obs = batch(2)
    obs["robot"]["qpos"] = torch.zeros(2, 3)
    with pytest.raises(ValueError, match="'robot/qpos' has 3 values per env, the layout expects 2"):
        flat.state(obs)
    with pytest.raises(KeyError, match="'robot/qf'"):
        leaf(obs, "robot/qf")
    with pytest.raises(TypeError, match="only Box and Dict"):
        ObsFlattener.from_space(gym.spaces.Dict({"k": gym.spaces.Discrete(3)}))
