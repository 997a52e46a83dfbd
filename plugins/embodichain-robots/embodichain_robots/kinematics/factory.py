"""Build a robot's part solvers from its ``solver_cfg`` (the ``build_solvers`` hook).

Example:
    >>> class MyArmCfg(RobotCfg):
    ...     def build_solvers(self, robot):
    ...         return build_part_solvers(robot, {"arm": IKSolverCfg(root_link_name="base",
    ...                                                               end_link_name="hand")})
"""

from __future__ import annotations

import importlib
from typing import Any, Mapping

from embodichain_core.config.errors import ConfigError
from embodichain_robots.kinematics.solver import IKSolverCfg

#: ``class_type`` -> "module:Class" of the solver implementations.
SOLVER_CLASSES = {
    "DLSSolver": "embodichain_robots.kinematics.solver:DLSSolver",
    "MjDLSSolver": "embodichain_robots.kinematics.mj_solver:MjDLSSolver",
}


def solver_class(class_type: str) -> type:
    """The solver class registered as ``class_type``."""
    if class_type not in SOLVER_CLASSES:
        raise ConfigError("solver_cfg.class_type", f"unknown solver {class_type!r}; known: {sorted(SOLVER_CLASSES)}")
    module, attr = SOLVER_CLASSES[class_type].split(":")
    return getattr(importlib.import_module(module), attr)


def build_part_solvers(robot: Any, solver_cfgs: Mapping[str, Any]) -> dict[str, Any]:
    """One solver per control part of ``robot`` (a built ``Robot``).

    Parts the robot does not have are skipped. Each solver's chain joints must
    be the part's joints (mimic joints aside), in the part's order; the solver's
    ``joint_ids`` become the robot joint ids.

    Raises:
        ConfigError: when a chain does not match its part.
    """
    out: dict[str, Any] = {}
    for part, cfg in (solver_cfgs or {}).items():
        if part not in robot.control_parts:
            continue
        cfg = IKSolverCfg.from_dict(cfg, f"solver_cfg.{part}") if isinstance(cfg, dict) else cfg
        solver = solver_class(cfg.class_type).from_model(cfg, robot.scene.model, prefix=f"{robot.uid}/")
        ids = [robot.joint_names.index(name) for name in solver.joint_names]
        expected = robot.get_joint_ids(part, remove_mimic=True)
        if ids != expected:
            raise ConfigError(f"solver_cfg.{part}", f"the chain {cfg.root_link_name!r} -> {cfg.end_link_name!r} "
                                                    f"has joints {ids}, but control part {part!r} has {expected}")
        solver.joint_ids = ids
        out[part] = solver
    return out
