"""A robot's ``control_parts`` checked against its joint names.

Each entry of ``control_parts.<part>`` is a joint name or a regex (full match). One that
matches no joint is a :class:`~embodichain_core.config.errors.ConfigError` at
``robot.control_parts.<part>[i]`` with the closest joint names. A file-based robot (``fpath``
or ``mjcf``) is checked when its config is validated, before the scene is built
(:func:`check_robot_joints`); a robot a plugin generates is checked when it is built
(:func:`match_part_patterns` from the robot entity).

Example:
    >>> match_part_patterns(["joint1", "joint2"], "robot", "arm", ["joint[12]"])
    [0, 1]
"""

from __future__ import annotations

import re
from typing import Any, Optional, Sequence

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.utils.suggest import did_you_mean

__all__ = ["match_part_patterns", "check_robot_joints", "file_joint_names"]


def match_part_patterns(names: Sequence[str], path: str, part: str, patterns: Any) -> list[int]:
    """Joint ids (in pattern order, no repeats) of one control part.

    Raises:
        ConfigError: at ``<path>.control_parts.<part>[i]`` for a pattern matching no joint
            (or an invalid regex), naming the closest joints.
    """
    if isinstance(patterns, str):
        patterns = [patterns]
    hits: list[int] = []
    for i, pattern in enumerate(patterns):
        where = f"{join_path(path, 'control_parts', str(part))}[{i}]"
        try:
            matched = [k for k, n in enumerate(names) if n == pattern or re.fullmatch(str(pattern), n)]
        except re.error as err:
            raise ConfigError(where, f"{pattern!r} is not a valid regex: {err}") from None
        if not matched:
            raise ConfigError(where, f"no joint of the robot matches {pattern!r}.{did_you_mean(str(pattern), names)}")
        hits += [k for k in matched if k not in hits]
    return hits


def file_joint_names(cfg: Any) -> Optional[list[str]]:
    """The joint names of a file-based robot (``mjcf`` or ``fpath``), ``None`` for a
    generated one or a file that does not load (the build reports that)."""
    from embodichain_core.sim.cfg import RobotCfg

    if type(cfg).build_spec is not RobotCfg.build_spec or not (cfg.mjcf or cfg.fpath):
        return None
    from embodichain_core.sim.scene_build.model_source import spec_from_cfg

    try:
        spec = spec_from_cfg(cfg)
    except Exception:  # noqa: BLE001 - a missing or broken file is the scene build's error
        return None
    return [j.name for j in spec.joints if j.name]


def check_robot_joints(cfg: Any, path: str = "robot") -> None:
    """Check every ``control_parts`` pattern of a file-based robot against its joints.

    Raises:
        ConfigError: the first pattern that matches no joint, at its path.
    """
    parts = getattr(cfg, "control_parts", None)
    if not isinstance(parts, dict) or not parts:
        return
    names = file_joint_names(cfg)
    if names is None:
        return
    for part, patterns in parts.items():
        match_part_patterns(names, path, str(part), patterns)
