"""embodichain-sensors: cameras (mono, stereo) and contact sensors for embodichain-core.

Names load lazily, so ``import embodichain_sensors`` is cheap.

Example:
    >>> from embodichain_sensors import CameraCfg
    >>> cam = CameraCfg(uid="cam", width=128, height=128, intrinsics=(100, 100, 64, 64),
    ...                 extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1, 0, 1), target=(0, 0, 0)))
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "CameraCfg": "embodichain_sensors.cfg",
    "StereoCameraCfg": "embodichain_sensors.cfg",
    "ContactSensorCfg": "embodichain_sensors.cfg",
    "ArticulationContactFilterCfg": "embodichain_sensors.cfg",
    "Camera": "embodichain_sensors.camera",
    "StereoCamera": "embodichain_sensors.stereo",
    "ContactSensor": "embodichain_sensors.contact",
    "SensorRenderer": "embodichain_sensors.renderer",
}

__all__ = list(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'embodichain_sensors' has no attribute {name!r}")
