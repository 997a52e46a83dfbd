"""Env checks and fixtures for plugin authors: ``make_env`` and ``check_batched_env``.

Example:
    >>> def test_my_task(make_env, check_batched_env):  # doctest: +SKIP
    ...     env = make_env("MyTask-v0", num_envs=2)
    ...     check_batched_env(env)

This module imports cheaply (it is loaded at every pytest start); gymnasium,
torch and the env classes are imported inside the functions.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator, Optional

import pytest


def make_env_instance(task: Any, num_envs: int = 2, cfg: Any = None, **kwargs: Any) -> Any:
    """Build an env from a task id (``gym.make``) or from a cfg object, quietly."""
    import gymnasium as gym

    if isinstance(task, str):
        if cfg is not None:
            cfg = cfg.copy()
            cfg.verbose = False
            return gym.make(task, cfg=cfg, num_envs=num_envs, **kwargs).unwrapped
        return gym.make(task, num_envs=num_envs, verbose=False, **kwargs).unwrapped
    from embodichain_core.envs import EmbodiedEnv

    cfg = task.copy()
    cfg.verbose = False
    cls = kwargs.pop("env_cls", EmbodiedEnv)
    return cls(cfg, num_envs=num_envs, **kwargs)


def check_batched_env(env: Any, steps: int = 3, seed: int = 0) -> None:
    """Assert the batched-env contract: shapes, dtypes, spaces, auto-reset bookkeeping.

    Resets with ``seed``, takes ``steps`` random actions, and checks that every
    observation leaf has a leading ``num_envs`` dim and lies in the observation
    space, rewards are float ``(N,)``, terminated/truncated bool ``(N,)``, info
    holds ``success``/``fail``/``elapsed_steps``, and a partial reset resets only
    the requested env.
    """
    import torch

    env = getattr(env, "unwrapped", env)
    n = env.num_envs
    obs, info = env.reset(seed=seed)
    _check_obs(obs, env.single_observation_space, n, "obs")
    for _ in range(steps):
        action = _sample_action(env)
        obs, reward, terminated, truncated, info = env.step(action)
        _check_obs(obs, env.single_observation_space, n, "obs")
        assert isinstance(reward, torch.Tensor), f"reward must be a torch tensor, got {type(reward).__name__}"
        assert reward.shape == (n,), f"reward shape {tuple(reward.shape)}, expected ({n},)"
        assert reward.dtype.is_floating_point, "reward must be floating point"
        for name, flag in (("terminated", terminated), ("truncated", truncated)):
            assert flag.shape == (n,), f"{name} must have shape ({n},), got {tuple(flag.shape)}"
            assert flag.dtype == torch.bool, f"{name} must be a bool tensor, got {flag.dtype}"
        for key in ("success", "fail", "elapsed_steps"):
            assert key in info, f"info is missing {key!r}"
    _check_partial_reset(env, n)


def _sample_action(env: Any) -> Any:
    import numpy as np
    import torch

    sample = env.action_space.sample()
    sample = (
        np.nan_to_num(np.clip(sample, -1.0, 1.0)) if np.issubdtype(np.asarray(sample).dtype, np.floating) else sample
    )
    return torch.as_tensor(sample, dtype=torch.float32) * 0.1


def _check_obs(obs: Any, space: Any, n: int, path: str) -> None:
    import numpy as np
    import torch

    if isinstance(obs, dict):
        assert set(obs) == set(space.spaces), f"{path}: keys {sorted(obs)} != space keys {sorted(space.spaces)}"
        for key, value in obs.items():
            _check_obs(value, space.spaces[key], n, f"{path}/{key}")
        return
    assert isinstance(obs, torch.Tensor), f"{path}: expected a tensor, got {type(obs).__name__}"
    assert obs.shape[0] == n, f"{path}: leading dim {obs.shape[0]} != num_envs {n}"
    assert tuple(obs.shape[1:]) == tuple(space.shape), f"{path}: shape {tuple(obs.shape[1:])} != space {space.shape}"
    arr = obs.detach().cpu().numpy()
    if np.issubdtype(arr.dtype, np.floating):
        assert not np.isnan(arr).any(), f"{path}: NaN in the observation"


def _check_partial_reset(env: Any, n: int) -> None:
    import torch

    env.step(_sample_action(env))
    before = env.elapsed_steps.clone()
    env.reset(options={"reset_ids": [0]})
    after = env.elapsed_steps
    assert int(after[0]) == 0, "reset_ids=[0] must reset env 0"
    if n > 1:
        assert torch.equal(after[1:], before[1:]), "a partial reset must not touch other envs"


@pytest.fixture
def make_env() -> Iterator[Callable[..., Any]]:
    """``make_env(task_id_or_cfg, num_envs=2, **kwargs)``; closes the envs afterwards."""
    made: list[Any] = []

    def factory(task: Any, num_envs: int = 2, cfg: Optional[Any] = None, **kwargs: Any) -> Any:
        env = make_env_instance(task, num_envs=num_envs, cfg=cfg, **kwargs)
        made.append(env)
        return env

    yield factory
    for env in made:
        env.close()


@pytest.fixture(name="check_batched_env")
def check_batched_env_fixture() -> Callable[..., None]:
    """The :func:`check_batched_env` function as a fixture."""
    return check_batched_env
