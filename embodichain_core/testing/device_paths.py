"""Test helpers that make a CPU simulation take the code paths of a GPU one.

The state route of entities and of the env's robot commands is chosen once, from the
backend's ``capabilities.host_arrays`` (:mod:`embodichain_core.sim.backend.state_route`).
A test compares the two routes on one machine:

* a whole env on the GPU's route: build it with backend ``warp`` on Warp's CPU device
  inside :func:`~embodichain_core.sim.backend.warp_device.cpu_device_route` (re-exported
  here; it is also what the device audit uses);
* one consumer on the torch route over any backend: give it :func:`without_host_arrays`
  of the sim, e.g. ``RobotIO(without_host_arrays(env.sim), env.robot, joints, n)``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from embodichain_core.sim.backend.warp_device import cpu_device_route

__all__ = ["cpu_device_route", "without_host_arrays"]


class _WithoutHostArrays:
    """``sim`` seen as a backend whose state is device memory: the same views and methods,
    ``capabilities.host_arrays`` False and no ``arrays``."""

    def __init__(self, sim: Any):
        self._sim = sim
        self.capabilities = dataclasses.replace(sim.capabilities, host_arrays=False)

    def __getattr__(self, name: str) -> Any:
        if name == "arrays":
            raise AttributeError(f"{type(self._sim).__name__} seen without host arrays has no 'arrays'")
        return getattr(self._sim, name)

    def __repr__(self) -> str:
        return f"without_host_arrays({self._sim!r})"


def without_host_arrays(sim: Any) -> Any:
    """``sim`` as a backend without host arrays: a consumer built on it (``RobotIO``, a
    :func:`~embodichain_core.sim.backend.state_route.state_route`) takes the torch route,
    writing into and reading from the same state as ``sim``."""
    return _WithoutHostArrays(sim)
