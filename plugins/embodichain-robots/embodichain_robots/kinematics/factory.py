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
from embodichain_robots.plugin import SOLVERS
from embodichain_robots.kinematics.solver import IKSolverCfg

#: ``class_type`` -> "module:Class" of this package's solvers (also registered as plugins' solvers).
SOLVER_CLASSES = SOLVERS


def solver_class(class_type: str) -> type[Any]:
    """The solver class of ``class_type``: this package's, else any plugin's (the solver registry)."""
    if class_type not in SOLVER_CLASSES:
        from embodichain_core.sim.entities.solvers import resolve_solver_class

        return resolve_solver_class(class_type, "solver_cfg.class_type")
    module, attr = SOLVER_CLASSES[class_type].split(":")
    return getattr(importlib.import_module(module), attr)


def solver_from_config(cls: Any, cfg: Mapping[str, Any], robot: Any, part: str) -> Any:
    """A ``cls`` solver (``DLSSolver`` or a subclass) for control part ``part`` of ``robot``.

    This is the ``from_config`` the solver registry calls for ``solver_cfg`` entries of
    any robot (see ``embodichain_register_solvers``). ``cfg`` holds
    :class:`IKSolverCfg` fields; errors name the key relative to the part entry.

    Raises:
        ConfigError: an unknown key, a missing link name, links that bound no chain,
            or a chain whose joints are not the part's joints.
    """
    ik = IKSolverCfg.from_dict(dict(cfg), "")
    for key in ("root_link_name", "end_link_name"):
        if not getattr(ik, key):
            raise ConfigError(key, f"the solver of part {part!r} needs a {key} (links: {robot.link_names})")
    try:
        solver = cls.from_model(ik, robot.scene.model, prefix=f"{robot.uid}/")
    except ValueError as err:
        key = "joint_names" if ik.joint_names is not None and "solver joints" in str(err) else "end_link_name"
        raise ConfigError(key, f"{err} (robot {robot.uid!r})") from None
    ids = [robot.joint_names.index(name) for name in solver.joint_names]
    expected = robot.get_joint_ids(part, remove_mimic=True)
    if ids != expected:
        raise ConfigError(
            "",
            f"the chain {ik.root_link_name!r} -> {ik.end_link_name!r} has joints "
            f"{solver.joint_names}, but control part {part!r} has "
            f"{[robot.joint_names[i] for i in expected]}",
        )
    solver.joint_ids = ids
    return solver


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
            raise ConfigError(
                f"solver_cfg.{part}",
                f"the chain {cfg.root_link_name!r} -> {cfg.end_link_name!r} "
                f"has joints {ids}, but control part {part!r} has {expected}",
            )
        solver.joint_ids = ids
        out[part] = solver
    return out
