"""Registrations of the embodichain-robots plugin.

Targets are lazy ``"module:attr"`` strings, so loading the plugin imports neither
torch nor mujoco; a robot's module is imported when a config names it.
"""

from __future__ import annotations

from embodichain_core.plugins import hookimpl

#: Registered robot name -> lazy config class.
ROBOTS: dict[str, str] = {
    "DexforceW1": "embodichain_robots.dexforce_w1.cfg:DexforceW1Cfg",
    "SevenDofArm": "embodichain_robots.seven_dof_arm.cfg:SevenDofArmCfg",
}


@hookimpl
def embodichain_register_robots(register) -> None:  # noqa: ANN001 - typed by the hookspec
    """Register ``DexforceW1`` and ``SevenDofArm``."""
    for name, target in ROBOTS.items():
        register(name, target)
