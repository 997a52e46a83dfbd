"""Fixtures of the embodichain-rl tests: small PushCube-v1 envs (short episodes), closed
after each test; ``rl_helpers`` is importable from the tests."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator
from typing import Any

import pytest

sys.path.append(os.path.dirname(__file__))

from embodichain_rl.env_factory import make_env  # noqa: E402

TASK = "PushCube-v1"


@pytest.fixture
def push_cube() -> Iterator[Callable[..., Any]]:
    """``push_cube(num_envs, max_episode_steps=5, **kw) -> EmbodiedEnv``; closed after the test."""
    envs: list[Any] = []

    def make(num_envs: int, max_episode_steps: int = 5, **kwargs: Any) -> Any:
        env = make_env(TASK, num_envs, seed=kwargs.pop("seed", 0), max_episode_steps=max_episode_steps, **kwargs)
        envs.append(env)
        return env

    yield make
    for env in envs:
        env.close()
