"""Fixtures of the embodichain-lerobot tests; helpers live in ``lerobot_helpers.py``.

Everything runs offline: the hub is disabled and the Hugging Face caches point
into a temporary folder before lerobot is imported.
"""

from __future__ import annotations

import os
import sys
import tempfile

_CACHE = tempfile.mkdtemp(prefix="embodichain-lerobot-hf-")
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")
os.environ.setdefault("HF_HOME", _CACHE)
os.environ.setdefault("HF_DATASETS_CACHE", os.path.join(_CACHE, "datasets"))
os.environ.setdefault("SVT_LOG", "1")

# appended, not prepended: the core tests import their own `conftest` module by name
sys.path.append(os.path.dirname(__file__))

from typing import Any, Callable, Iterator  # noqa: E402

import pytest  # noqa: E402


@pytest.fixture
def make_env() -> Iterator[Callable[..., Any]]:
    """``make_env(cfg) -> ScriptedEnv``; envs are closed after the test."""
    from lerobot_helpers import ScriptedEnv

    envs: list[Any] = []

    def make(cfg: Any) -> Any:
        env = ScriptedEnv(cfg)
        envs.append(env)
        return env

    yield make
    for env in envs:
        try:
            env.close()
        except Exception:  # a test may have broken its env on purpose
            pass


def pytest_configure(config: Any) -> None:
    # lerobot stores (1,)-shaped features as scalars and histograms boolean ones: both warn on every frame
    config.addinivalue_line("filterwarnings", "ignore:Conversion of an array with ndim > 0:DeprecationWarning")
    config.addinivalue_line("filterwarnings", "ignore:Converting input from bool:RuntimeWarning")
    # PyAV decoding (torchcodec needs system FFmpeg) goes through torchvision's deprecated reader
    config.addinivalue_line("filterwarnings", "ignore:The video decoding and encoding capabilities:UserWarning")


@pytest.fixture
def task_id() -> Iterator[str]:
    """A fresh task id registered for ``DemoPush`` (the scripted demo env of the run-env tests)."""
    import uuid

    import gymnasium as gym
    from test_lerobot_run_env import DemoPush

    from embodichain_core.envs.registration import register_env

    uid = f"LeRobotDemo{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(DemoPush)
    yield uid
    gym.registry.pop(uid, None)
