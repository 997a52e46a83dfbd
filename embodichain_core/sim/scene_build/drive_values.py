"""One joint's drive value from a ``JointDrivePropertiesCfg`` field.

A field is a number (every joint) or a ``{joint name or regex: number}`` mapping. The
mapping is read without regard to its order:

* an entry named exactly like the joint wins over every pattern;
* otherwise the patterns that fully match the joint give its value; patterns that match
  the same joint with different values are a :class:`ConfigError` naming both, the joint
  and the config key (give the joint its own entry, or narrow a pattern);
* a joint no entry matches gets the field's default.

Example:
    >>> joint_value({".*": 1e4, "finger_joint": 10.0}, "finger_joint", "drive_pros.stiffness")
    10.0
    >>> joint_value({".*": 1e4, "finger_.*": 10.0}, "finger_joint", "drive_pros.stiffness")  # doctest: +SKIP
    ConfigError: drive_pros.stiffness: joint 'finger_joint' matches both '.*' (= 10000) and 'finger_.*' (= 10); ...
"""

from __future__ import annotations

import math
import re
from typing import Any

from embodichain_core.config.errors import ConfigError, join_path

__all__ = ["joint_value"]


def joint_value(values: Any, joint: str, path: str) -> float:
    """The drive value of ``joint``: ``values`` itself, or its mapping's entry for the joint.

    Args:
        values: a number, or ``{joint name or regex (full match): number}``.
        joint: the joint's name.
        path: the field's config path (``robot.drive_pros.stiffness``), for errors.

    Returns:
        The value; NaN when a mapping has no entry for the joint (the caller's default).

    Raises:
        ConfigError: not a number or mapping, a pattern that is no regex, or two patterns
            that match ``joint`` with different values.
    """
    if isinstance(values, dict):
        return _mapped(values, joint, path)
    try:
        return float(values)
    except (TypeError, ValueError) as err:
        raise ConfigError(path, f"expected a number or a {{regex: number}} mapping, got {values!r}") from err


def _mapped(values: dict, joint: str, path: str) -> float:
    if joint in values:
        return float(values[joint])
    hits = [(str(key), float(value)) for key, value in values.items() if _matches(str(key), joint, path)]
    if not hits:
        return math.nan
    first, value = hits[0]
    for other, other_value in hits[1:]:
        if other_value != value:
            raise ConfigError(
                path,
                f"joint {joint!r} matches both {first!r} (= {value:g}) and {other!r} (= {other_value:g}); "
                f"give the joint its own entry ({joint!r}: value; an exact name wins over patterns) "
                "or narrow one pattern so they match different joints",
            )
    return value


def _matches(pattern: str, joint: str, path: str) -> bool:
    try:
        return re.fullmatch(pattern, joint) is not None
    except re.error as err:
        raise ConfigError(join_path(path, pattern), f"not a valid joint regex: {err}") from err
