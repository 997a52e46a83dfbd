"""Part solvers of a robot built from its ``solver_cfg`` through the solver registry.

A robot section of any config (a plain ``RobotCfg`` with ``fpath``/``mjcf`` included)
may carry ``"solver_cfg": {part: {"class_type": name, ...}}``. Each entry builds the
kinematics solver of one control part with the class a plugin registered as ``name``
(the ``embodichain_register_solvers`` hook); the core holds no solver code. Before
the class is called, the core checks what every chain solver needs: the part exists,
``root_link_name`` / ``end_link_name`` (when given) are links of the robot. After, the
solver's joints must be the part's joints (mimic joints aside). Every failure is a
:class:`~embodichain_core.config.errors.ConfigError` at the key's path
(``robot.solver_cfg.arm.end_link_name``) with the closest valid choice.

Example:
    >>> cfg = RobotCfg.from_dict({"uid": "arm", "fpath": "arm.urdf", "control_parts": {"arm": ["j[1-6]"]},
    ...     "solver_cfg": {"arm": {"class_type": "DLSSolver", "root_link_name": "base",
    ...                            "end_link_name": "flange"}}})  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Mapping

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.utils.configclass import is_configclass
from embodichain_core.utils.suggest import did_you_mean

#: Keys of a part entry that name links of the robot (checked before the solver class runs).
LINK_KEYS = ("root_link_name", "end_link_name")


def resolve_solver_class(name: Any, path: str) -> Any:
    """The solver class registered as ``name``; a ``ConfigError`` at ``path`` otherwise."""
    from embodichain_core.plugins import AmbiguousNameError, get_solver_class, solver_registry

    if not isinstance(name, str) or not name:
        known = ", ".join(solver_registry().names()) or "none; install a plugin providing solvers"
        raise ConfigError(path, f"every solver_cfg part needs a 'class_type' naming a solver (registered: {known})")
    try:
        return get_solver_class(name)
    except AmbiguousNameError as err:
        raise ConfigError(path, str(err)) from None
    except KeyError as err:
        raise ConfigError(path, str(err.args[0]) if err.args else str(err)) from None


def part_entry(cfg: Any, path: str) -> dict[str, Any]:
    """A part's solver settings as a plain dict (from a mapping or a config class)."""
    if is_configclass(cfg):
        return dict(cfg.to_dict())
    if isinstance(cfg, Mapping):
        return dict(cfg)
    raise ConfigError(path, f"expected a mapping of solver settings, got {type(cfg).__name__}")


def check_part_links(robot: Any, entry: Mapping[str, Any], path: str) -> None:
    """``root_link_name`` / ``end_link_name`` of ``entry`` must be links of ``robot``."""
    for key in LINK_KEYS:
        link = entry.get(key)
        if link is None:
            continue
        if not isinstance(link, str) or link not in robot.link_names:
            raise ConfigError(
                join_path(path, key),
                f"robot {robot.uid!r} has no link {link!r}.{did_you_mean(str(link), robot.link_names)}",
            )


def check_solver_joints(robot: Any, part: str, solver: Any, path: str) -> None:
    """The solver's ``joint_ids`` must be the part's joints (mimic joints aside), in order."""
    ids = [int(j) for j in getattr(solver, "joint_ids", [])]
    expected = robot.get_joint_ids(part, remove_mimic=True)
    if ids != expected:
        got = [robot.joint_names[i] for i in ids if 0 <= i < robot.dof]
        want = [robot.joint_names[i] for i in expected]
        raise ConfigError(
            path,
            f"the solver's chain has joints {got}, but control part {part!r} of "
            f"{robot.uid!r} has {want}; pick the links that bound exactly the part's joints",
        )


def build_cfg_solvers(robot: Any, solver_cfg: Any, path: str) -> dict[str, Any]:
    """One solver per entry of ``solver_cfg`` (``{part: {"class_type": ..., ...}}``).

    Args:
        robot: the built :class:`~embodichain_core.sim.entities.robot.Robot`.
        solver_cfg: the robot config's ``solver_cfg``.
        path: config path of ``solver_cfg`` (``"robot.solver_cfg"``), for errors.

    Returns:
        ``{part: solver}``.

    Raises:
        ConfigError: not a mapping, an unknown part, solver or link, or a chain whose
            joints are not the part's, at the offending key's path.
    """
    if solver_cfg is None:
        return {}
    if not isinstance(solver_cfg, Mapping):
        raise ConfigError(path, f"expected a {{part: solver settings}} mapping, got {type(solver_cfg).__name__}")
    out: dict[str, Any] = {}
    for part, cfg in solver_cfg.items():
        where = join_path(path, str(part))
        if part not in robot.control_parts:
            raise ConfigError(
                where,
                f"robot {robot.uid!r} has no control part {part!r}."
                f"{did_you_mean(str(part), robot.control_parts) or ' Define it in control_parts.'}",
            )
        entry = part_entry(cfg, where)
        solver_class = resolve_solver_class(entry.get("class_type"), join_path(where, "class_type"))
        check_part_links(robot, entry, where)
        try:
            solver = solver_class.from_config(entry, robot, str(part))
        except ConfigError as err:
            raise err.under(where) from err
        check_solver_joints(robot, str(part), solver, where)
        out[str(part)] = solver
    return out
