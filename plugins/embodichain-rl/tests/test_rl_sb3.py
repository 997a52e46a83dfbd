"""The Stable-Baselines3 adapter and the single-env view: the libraries' own checks,
terminal observations and time limits as SB3 expects them, SB3 PPO end to end."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env as gymnasium_check_env
from stable_baselines3 import PPO
from stable_baselines3.common.env_checker import check_env as sb3_check_env
from stable_baselines3.common.vec_env import VecEnv

from embodichain_rl.sb3_env import Sb3VecEnv
from embodichain_rl.single_env import SingleEnvView


def test_single_env_view_passes_gymnasium_and_sb3_checks(push_cube) -> None:
    view = SingleEnvView(push_cube(1, max_episode_steps=3))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infinity.*")  # unbounded float observations
        gymnasium_check_env(view, skip_render_check=True)
        sb3_check_env(view, warn=False)
    obs, _ = view.reset(seed=0)
    assert obs.shape == view.observation_space.shape
    assert obs.dtype == np.float32
    out = [view.step(np.zeros(7, np.float32)) for _ in range(3)]
    assert [o[3] for o in out] == [False, False, True]
    assert isinstance(out[0][1], float)
    with pytest.raises(ValueError, match="num_envs=1"):
        SingleEnvView(push_cube(2))


def test_vec_env_conformance(push_cube) -> None:
    venv = Sb3VecEnv(push_cube(3))
    assert isinstance(venv, VecEnv)
    assert venv.num_envs == 3
    assert venv.observation_space.shape == (venv.flattener.state_dim,)
    assert venv.action_space.shape == (7,)
    assert np.all(np.isfinite(venv.action_space.high))
    assert venv.get_attr("max_episode_steps") == [5, 5, 5]
    assert venv.get_attr("num_envs", [1]) == [3]
    assert venv.env_is_wrapped(object) == [False] * 3
    venv.seed(7)
    first = venv.reset()
    venv.seed(7)
    assert first.shape == (3, venv.flattener.state_dim)
    assert np.array_equal(venv.reset(), first)
    with pytest.raises(ValueError, match="every env"):
        venv.set_attr("max_episode_steps", 3, indices=[0])


def test_terminal_observation_and_time_limit(push_cube) -> None:
    venv = Sb3VecEnv(push_cube(2, max_episode_steps=3))
    venv.reset()
    actions = np.full((2, 7), 0.5, np.float32)
    for _ in range(2):
        obs, reward, dones, infos = venv.step(actions)
        assert reward.shape == (2,)
        assert not dones.any()
        assert infos == [{}, {}]
    obs, reward, dones, infos = venv.step(actions)
    assert dones.tolist() == [True, True]
    for i, info in enumerate(infos):
        assert info["TimeLimit.truncated"] is True
        assert info["episode"]["l"] == 3
        terminal = info["terminal_observation"]
        assert terminal.shape == obs[i].shape
        assert not np.allclose(terminal, obs[i])
    qpos = venv.flattener.state_paths.index("robot/qpos")
    offset = sum(venv.flattener.state_sizes[:qpos])
    reset_qpos = torch.as_tensor(obs[:, offset : offset + 7])
    assert torch.allclose(reset_qpos, venv.env.robot.get_qpos()[:, :7].float(), atol=1e-5)


def test_sb3_ppo_learns_a_few_steps(push_cube, tmp_path) -> None:
    venv = Sb3VecEnv(push_cube(4, max_episode_steps=6))
    model = PPO("MlpPolicy", venv, n_steps=8, batch_size=16, n_epochs=2, device="cpu", seed=0)
    model.learn(total_timesteps=64)
    assert model.num_timesteps == 64
    assert len(model.ep_info_buffer) >= 4
    model.save(str(tmp_path / "m.zip"))
    action, _ = PPO.load(str(tmp_path / "m.zip"), device="cpu").predict(venv.reset(), deterministic=True)
    assert action.shape == (4, 7)


def test_camera_images_become_a_flat_dict(push_cube) -> None:
    venv = Sb3VecEnv(push_cube(2, max_episode_steps=2, video=True, video_size=(40, 30)))
    key = "sensor/rl_video/color"
    assert set(venv.observation_space.spaces) == {"state", key}
    assert venv.observation_space[key].shape == (30, 40, 4)
    assert venv.observation_space[key].dtype == np.uint8
    obs = venv.reset()
    assert obs["state"].shape == (2, venv.flattener.state_dim)
    assert obs[key].shape == (2, 30, 40, 4)
    venv.step(np.zeros((2, 7), np.float32))
    _, _, dones, infos = venv.step(np.zeros((2, 7), np.float32))
    assert dones.all()
    assert set(infos[1]["terminal_observation"]) == {"state", key}
    assert infos[1]["terminal_observation"][key].shape == (30, 40, 4)
    view = SingleEnvView(push_cube(1, max_episode_steps=2, video=True, video_size=(40, 30)))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infinity.*")
        sb3_check_env(view, warn=False)
