"""Registrations of embodichain-sensors: lazy ``"module:attr"`` strings only, so
loading the plugin imports neither MuJoCo nor torch."""

from __future__ import annotations

from embodichain_core.plugins import SensorRegister, hookimpl

#: sensor_type -> (config class, sensor class)
SENSORS: dict[str, tuple[str, str]] = {
    "Camera": ("embodichain_sensors.cfg:CameraCfg", "embodichain_sensors.camera:Camera"),
    "StereoCamera": ("embodichain_sensors.cfg:StereoCameraCfg", "embodichain_sensors.stereo:StereoCamera"),
    "ContactSensor": ("embodichain_sensors.cfg:ContactSensorCfg", "embodichain_sensors.contact:ContactSensor"),
}


@hookimpl
def embodichain_register_sensors(register: SensorRegister) -> None:
    """Register ``Camera``, ``StereoCamera`` and ``ContactSensor``."""
    for sensor_type, (cfg_class, sensor_class) in SENSORS.items():
        register(sensor_type, cfg_class, sensor_class)
