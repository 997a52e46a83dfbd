"""Plausible physical scales of a scene, checked at build.

A value can be a valid number and still be nonsense for a robot-learning scene: an object
a thousand kilometres away (MuJoCo then reports "huge value in QPOS" and carries on), a
fork of a million kilograms, a friction coefficient of 1e9. :func:`check_plausible`
rejects such values with a :class:`~embodichain_core.config.errors.ConfigError` at their
config path, naming the bound and how to raise it. The bounds (:data:`DEFAULT_LIMITS`)
are generous; an unusual scene raises one in ``sim_cfg.physical_limits`` (the gym
config's top-level ``physical_limits``), e.g. ``{"position": 5000}``.

Example:
    >>> plausible_limits({"mass": 1e5})["mass"]
    100000.0
"""

from __future__ import annotations

from typing import Any, Iterator

from embodichain_core.config.checks import check_number, describe, is_number
from embodichain_core.config.errors import ConfigError, join_path

__all__ = ["DEFAULT_LIMITS", "LIMIT_PATH", "plausible_limits", "check_plausible"]

#: Largest magnitude accepted per quantity: ``position`` (each coordinate of an entity's
#: initial position, metres), ``mass`` (kg), ``density`` (kg/m^3; osmium is 22590),
#: ``friction`` (static and dynamic coefficients; rubber on concrete is about 1).
DEFAULT_LIMITS: dict[str, float] = {"position": 1000.0, "mass": 1.0e4, "density": 1.0e5, "friction": 10.0}
#: Where a config raises a bound.
LIMIT_PATH = "sim_cfg.physical_limits"


def plausible_limits(overrides: Any) -> dict[str, float]:
    """:data:`DEFAULT_LIMITS` with the config's overrides (``{quantity: bound > 0}``).

    Raises:
        ConfigError: an override that is not a mapping of known quantities to numbers > 0.
    """
    if overrides is None:
        return dict(DEFAULT_LIMITS)
    if not isinstance(overrides, dict):
        raise ConfigError(LIMIT_PATH, f"expected a mapping {{quantity: bound}}, got {describe(overrides)}")
    limits = dict(DEFAULT_LIMITS)
    for key, value in overrides.items():
        where = join_path(LIMIT_PATH, str(key))
        if key not in DEFAULT_LIMITS:
            raise ConfigError(where, f"unknown quantity {key!r}; the bounds are {', '.join(DEFAULT_LIMITS)}")
        limits[key] = check_number(value, where, low=0.0, low_open=True)
    return limits


def _entities(cfg: Any) -> Iterator[tuple[Any, str]]:
    """``(entity cfg, config path)`` of the robot, articulations, objects and group members."""
    yield cfg.robot, "robot"
    for key in ("articulation", "articulation_cfg", "background", "rigid_object"):
        for i, item in enumerate(getattr(cfg, key, None) or []):
            yield item, f"{key}[{i}]"
    for i, group in enumerate(getattr(cfg, "rigid_object_group", None) or []):
        for name, member in dict(group.rigid_objects).items():
            yield member, join_path(f"rigid_object_group[{i}]", "rigid_objects", str(name))


def _beyond(value: Any, bound: float, where: str, quantity: str, unit: str) -> None:
    if is_number(value) and abs(float(value)) > bound:
        raise ConfigError(
            where,
            f"{value:g}{unit} is beyond the plausible {quantity} bound of {bound:g}{unit}; if the scene really "
            f"needs it, raise the bound with {LIMIT_PATH}.{quantity} (top-level 'physical_limits' in a gym config)",
        )


def check_plausible(cfg: Any) -> None:
    """Check positions, masses, densities and frictions of every entity of ``cfg`` (an
    ``EmbodiedEnvCfg``) against :func:`plausible_limits` of ``cfg.sim_cfg.physical_limits``.

    Raises:
        ConfigError: the first implausible value, at its config path.
    """
    limits = plausible_limits(getattr(cfg.sim_cfg, "physical_limits", None))
    for entity, path in _entities(cfg):
        for k, coord in enumerate(entity.init_pos or ()):
            _beyond(coord, limits["position"], f"{join_path(path, 'init_pos')}[{k}]", "position", " m")
        pose = getattr(entity, "init_local_pose", None)
        if pose is not None:
            for k in range(3):
                where = f"{join_path(path, 'init_local_pose')}[{k}][3]"
                _beyond(pose[k][3], limits["position"], where, "position", " m")
        attrs, where = entity.attrs, join_path(path, "attrs")
        _beyond(attrs.mass, limits["mass"], join_path(where, "mass"), "mass", " kg")
        _beyond(attrs.density, limits["density"], join_path(where, "density"), "density", " kg/m^3")
        for name in ("static_friction", "dynamic_friction"):
            _beyond(getattr(attrs, name), limits["friction"], join_path(where, name), "friction", "")
