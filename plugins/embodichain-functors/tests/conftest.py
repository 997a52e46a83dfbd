"""Fixtures of the functor tests; helpers live in ``functors_testlib``."""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Iterator

import pytest

sys.path.append(os.path.dirname(__file__))  # append: the core tests import their own `conftest`

from functors_testlib import scene_cfg  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402


@pytest.fixture
def build() -> Iterator[Callable[..., EmbodiedEnv]]:
    """Factory ``build(cfg=None, **overrides) -> env``; envs are closed after the test."""
    envs: list[EmbodiedEnv] = []

    def make(cfg: EmbodiedEnvCfg | None = None, **overrides: Any) -> EmbodiedEnv:
        env = EmbodiedEnv(cfg if cfg is not None else scene_cfg(**overrides))
        envs.append(env)
        return env

    yield make
    for env in envs:
        env.close()
