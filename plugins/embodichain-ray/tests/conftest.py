"""Fixtures of the embodichain-ray tests: a tiny PickFork config (64x64 stereo camera,
10-step episodes that the recorder keeps), offline Hugging Face caches, and Ray shut
down after every test."""

from __future__ import annotations

import json
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

_CACHE = tempfile.mkdtemp(prefix="embodichain-ray-hf-")
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")
os.environ.setdefault("HF_HOME", _CACHE)
os.environ.setdefault("HF_DATASETS_CACHE", os.path.join(_CACHE, "datasets"))
os.environ.setdefault("SVT_LOG", "1")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")

sys.path.append(os.path.dirname(__file__))

import pytest  # noqa: E402  (after the environment above: lerobot and Ray read it on import)

TINY = Path(__file__).parent / "data" / "tiny_pick_fork.json"


@pytest.fixture
def tiny_config(tmp_path: Path) -> Callable[..., str]:
    """``tiny_config(**top_level_overrides) -> path`` of a copy of the tiny config."""

    def make(**overrides: Any) -> str:
        data = json.loads(TINY.read_text())
        data.update(overrides)
        path = tmp_path / f"tiny_{len(list(tmp_path.glob('tiny_*.json')))}.json"
        path.write_text(json.dumps(data))
        return str(path)

    return make


@pytest.fixture(autouse=True)
def no_ray_left() -> Iterator[None]:
    """Every test ends with Ray shut down (also when it failed half-way)."""
    yield
    if "ray" in sys.modules:
        import ray

        if ray.is_initialized():
            ray.shutdown()


def pytest_configure(config: Any) -> None:
    config.addinivalue_line("markers", "slow: takes more than ~20 s (deselect with -m 'not slow')")
    config.addinivalue_line("filterwarnings", "ignore:Conversion of an array with ndim > 0:DeprecationWarning")
    config.addinivalue_line("filterwarnings", "ignore:Converting input from bool:RuntimeWarning")
    config.addinivalue_line("filterwarnings", "ignore:The video decoding and encoding capabilities:UserWarning")
