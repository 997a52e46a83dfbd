"""``gym.make_vec`` in every vectorization mode gives rewards and flags of shape
``(num_envs,)``: the vector entry point (the batched env itself), and gymnasium's sync and
async vector envs, whose sub-envs are ``UnbatchedEnv`` s (single-env layout, last
observation on done) with or without ``wrappers=[UnbatchedEnv]``."""

import copy
import warnings

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

from embodichain_core.gym_vector import BatchedEnvSpec, SingleEnvEntryPoint, UnbatchedEnv

pytestmark = pytest.mark.usefixtures("fixture_plugins")
TASK = "FixtureReach-v0"  # 3 actions, 15-step episodes (tests/fixture_plugins)


@pytest.mark.parametrize(
    "mode, vector_kwargs, wrappers",
    [("sync", {}, []), ("async", {"context": "spawn"}, []), ("sync", {}, [UnbatchedEnv])],
)
def test_gymnasium_vector_envs_over_unbatched_envs(mode: str, vector_kwargs: dict, wrappers: list) -> None:
    venv = gym.make_vec(
        TASK, num_envs=2, vectorization_mode=mode, vector_kwargs=vector_kwargs, wrappers=wrappers, verbose=False
    )
    try:
        assert venv.single_observation_space["object"]["cube_pos"].shape == (3,)
        assert venv.single_action_space.shape == (3,)
        assert venv.action_space.shape == (2, 3)
        obs, _ = venv.reset(seed=0)
        assert obs["object"]["cube_pos"].shape == (2, 3)
        for step in range(1, 16):
            obs, reward, terminated, truncated, _ = venv.step(np.zeros((2, 3), np.float32))
            assert reward.shape == terminated.shape == truncated.shape == (2,)
            assert truncated.tolist() == [step == 15] * 2
    finally:
        venv.close()


def test_vector_entry_point_is_the_batched_env() -> None:
    venv = gym.make_vec(TASK, num_envs=3, verbose=False)
    _, reward, terminated, truncated, _ = venv.step(torch.zeros(3, 3))
    assert reward.shape == terminated.shape == truncated.shape == (3,)
    venv.close()


def test_unbatched_env_layout_and_errors() -> None:
    env = UnbatchedEnv(gym.make(TASK, verbose=False))
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert isinstance(info["success"], bool)
    for _ in range(15):
        obs, reward, terminated, truncated, info = env.step(np.zeros(3, np.float32))
    assert isinstance(reward, float)
    assert truncated is True
    assert isinstance(terminated, bool)
    assert info["elapsed_steps"] == 15  # the info of the episode's last step, not of the reset
    with pytest.raises(ValueError, match="num_envs=1"):
        UnbatchedEnv(gym.make(TASK, num_envs=2, verbose=False))


def test_unbatched_env_passes_gymnasium_check_env() -> None:
    # check_env rebuilds the env from env.spec (RecordConstructorArgs), then checks the spaces,
    # seeding and the step/reset layout of the single-env API
    env = UnbatchedEnv(gym.make(TASK, verbose=False))
    try:
        assert env.spec.additional_wrappers[-1].name == "UnbatchedEnv"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # the checker's advice on infinite Box bounds
            check_env(env, skip_render_check=True)
    finally:
        env.close()


def test_gym_make_stays_batched_and_only_make_vec_copies_unbatch() -> None:
    spec = gym.registry[TASK]
    assert isinstance(spec, BatchedEnvSpec)
    env = gym.make(TASK, verbose=False)
    assert not isinstance(env, UnbatchedEnv)
    assert env.unwrapped.num_envs == 1
    _, reward, *_ = env.step(torch.zeros(1, 3))
    assert reward.shape == (1,)
    env.close()
    copied = copy.deepcopy(spec)  # what gym.make_vec builds its sub-envs from
    assert isinstance(copied.entry_point, SingleEnvEntryPoint)
    assert copied.entry_point.entry_point == spec.entry_point
    assert copied.kwargs == spec.kwargs
    assert copied.vector_entry_point is spec.vector_entry_point


def test_single_env_entry_point_rejects_what_is_no_gymnasium_env() -> None:
    with pytest.raises(TypeError, match="built a dict, not a gymnasium.Env"):
        SingleEnvEntryPoint(lambda **kwargs: dict(kwargs))(num_envs=1)
    twice = UnbatchedEnv(UnbatchedEnv(gym.make(TASK, verbose=False)))  # passthrough: same layout
    twice.reset(seed=0)
    _, reward, terminated, truncated, _ = twice.step(np.zeros(3, np.float32))
    assert isinstance(reward, float)
    assert terminated is False
    assert truncated is False
    twice.close()
