"""``ProceduralRobotCfg``: the shared base of this package's robot configs.

It adds what EmbodiChain's ``merge_robot_cfg`` does to ``from_dict``: user
``drive_pros`` dicts are deep-merged into the robot's defaults (your entries win over the
default groups they overlap: :func:`layer_patterns`) and ``solver_cfg`` is patched per
part (a part dict without ``class_type`` only updates the default solver, e.g. its ``tcp``). It also
builds the part solvers for the ``Robot`` (:meth:`build_solvers`).
"""

from __future__ import annotations

import re
from typing import Any

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import JointDrivePropertiesCfg, RobotCfg
from embodichain_core.utils.configclass import configclass, is_configclass
from embodichain_robots.kinematics.solver import IKSolverCfg


@configclass
class ProceduralRobotCfg(RobotCfg):
    """A robot whose model is generated in code (override :meth:`build_spec`)."""

    @classmethod
    def _build_from_dict(cls, data: dict, path: str) -> Any:
        data = dict(data)
        drive, solvers = data.pop("drive_pros", None), data.pop("solver_cfg", None)
        try:
            cfg = super()._build_from_dict(data, path)
        except ConfigError as err:
            raise err.under(path) if path and not err.path.startswith(path) else err
        if drive is not None:
            cfg.drive_pros = merge_drive_pros(cfg.drive_pros, drive, _join(path, "drive_pros"))
        if solvers is not None:
            cfg.solver_cfg = merge_solvers(cfg.solver_cfg or {}, solvers, _join(path, "solver_cfg"))
        return cfg

    def build_solvers(self, robot: Any) -> dict[str, Any]:
        """One IK/FK solver per entry of ``solver_cfg`` (the ``Robot`` hook)."""
        from embodichain_robots.kinematics.factory import build_part_solvers

        return build_part_solvers(robot, self.solver_cfg or {})


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def merge_drive_pros(default: JointDrivePropertiesCfg, user: Any, path: str) -> JointDrivePropertiesCfg:
    """``default`` patched with ``user`` (a cfg replaces it; a dict is merged key by key, a
    ``{joint regex: value}`` mapping by :func:`layer_patterns`: your entries win)."""
    if is_configclass(user):
        return user
    if not isinstance(user, dict):
        raise ConfigError(path, f"expected a mapping, got {type(user).__name__}")
    merged = default.to_dict()
    for key, value in user.items():
        old = merged.get(key)
        merged[key] = layer_patterns(value, old) if isinstance(value, dict) and isinstance(old, dict) else value
    return JointDrivePropertiesCfg.from_dict(merged, path)


def layer_patterns(user: dict, default: dict) -> dict:
    """``user``'s entries, then ``default``'s narrowed to the joints none of ``user``'s
    patterns match, so a user pattern overrides a default group it overlaps (the core
    rejects two patterns that give one joint different values).

    A default pattern ``P`` becomes ``(?!(?:U1|U2)$)(?:P)`` (a negative lookahead on the
    user's patterns); exact joint names need no narrowing (an exact name always wins). The
    merge is idempotent: a default already narrowed in ``user`` (a config written by
    ``to_dict`` and read again) is not added twice.
    """
    patterns = [str(k) for k in user if not _is_name(str(k)) and not _narrowed_from(str(k), default)]
    out = dict(user)
    for pattern, value in default.items():
        if pattern in user or any(_narrowed_from(str(k), {pattern: value}) for k in user):
            continue
        out[_narrow(str(pattern), patterns)] = value
    return out


def _is_name(key: str) -> bool:
    return re.escape(key) == key


def _narrow(pattern: str, user_patterns: list[str]) -> str:
    return f"(?!(?:{'|'.join(user_patterns)})$)(?:{pattern})" if user_patterns else pattern


def _narrowed_from(key: str, default: dict) -> bool:
    return key.startswith("(?!(?:") and any(key.endswith(f")$)(?:{p})") for p in default)


def merge_solvers(default: dict, user: Any, path: str) -> dict[str, IKSolverCfg]:
    """Per-part patch: a dict without ``class_type`` updates the default part solver."""
    if not isinstance(user, dict):
        raise ConfigError(path, f"expected a {{part: solver}} mapping, got {type(user).__name__}")
    out = dict(default)
    for part, value in user.items():
        if isinstance(value, IKSolverCfg):
            out[part] = value
            continue
        if not isinstance(value, dict):
            raise ConfigError(f"{path}.{part}", f"expected a mapping, got {type(value).__name__}")
        base = out.get(part)
        if isinstance(base, dict):
            base = IKSolverCfg.from_dict(base, f"{path}.{part}")
        merged = value if ("class_type" in value or base is None) else {**base.to_dict(), **value}
        out[part] = IKSolverCfg.from_dict(merged, f"{path}.{part}")
    return out
