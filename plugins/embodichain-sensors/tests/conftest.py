"""Fixtures of the sensor tests; scene helpers live in ``sensors_helpers.py``."""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Iterator

import pytest

# appended, not prepended: the core tests import their own `conftest` module by name
sys.path.append(os.path.dirname(__file__))

from sensors_helpers import make_scene  # noqa: E402


@pytest.fixture
def scene_factory() -> Iterator[Callable[..., Any]]:
    """``scene_factory(*sensor_cfgs, **kw) -> (scene, sensors)``; sensors closed after the test."""
    made: list[Any] = []

    def make(*cfgs: Any, **kwargs: Any) -> Any:
        scene, sensors = make_scene(*cfgs, **kwargs)
        made.extend(sensors)
        return scene, sensors

    yield make
    for sensor in made:
        sensor.close()
