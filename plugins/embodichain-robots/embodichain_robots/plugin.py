"""Registrations of the embodichain-robots plugin.

Robots and kinematics solvers (``solver_cfg.<part>.class_type``). Targets are lazy
``"module:attr"`` strings, so loading the plugin imports neither torch nor mujoco; a
robot's (or solver's) module is imported when a config names it.
"""

from __future__ import annotations

from embodichain_core.plugins import hookimpl

#: Registered robot name -> lazy config class.
ROBOTS: dict[str, str] = {
    "DexforceW1": "embodichain_robots.dexforce_w1.cfg:DexforceW1Cfg",
    "SevenDofArm": "embodichain_robots.seven_dof_arm.cfg:SevenDofArmCfg",
}
#: Registered solver name (a ``class_type``) -> lazy solver class.
SOLVERS: dict[str, str] = {
    "DLSSolver": "embodichain_robots.kinematics.solver:DLSSolver",
    "MjDLSSolver": "embodichain_robots.kinematics.mj_solver:MjDLSSolver",
}


@hookimpl
def embodichain_register_robots(register) -> None:  # noqa: ANN001 - typed by the hookspec
    """Register ``DexforceW1`` and ``SevenDofArm``."""
    for name, target in ROBOTS.items():
        register(name, target)


@hookimpl
def embodichain_register_solvers(register) -> None:  # noqa: ANN001 - typed by the hookspec
    """Register ``DLSSolver`` and ``MjDLSSolver`` for ``solver_cfg`` of any robot."""
    for name, target in SOLVERS.items():
        register(name, target)
