"""Physics randomization: masses, centres of mass, friction; joint damping, stiffness and
drive gains live in :mod:`.joints` (re-exported here). Every value is drawn per env from
each env's episode stream (``env.rng``) and written into the per-env model fields of ``env_ids`` only."""

from __future__ import annotations

import warnings
from typing import Any, Optional, Union

import numpy as np

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject

from embodichain_functors._common import (
    ParamError,
    as_range,
    entity_of,
    env_ids_of,
    uniform_np,
    validated,
)
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._entities import link_body_ids, rigid_bodies
from embodichain_functors._sim import write_model
from embodichain_functors.randomization.joints import (  # re-exported
    randomize_joint_damping,
    randomize_joint_drive,
    randomize_joint_stiffness,
)

__all__ = [
    "randomize_rigid_object_mass",
    "randomize_rigid_object_center_of_mass",
    "randomize_articulation_mass",
    "randomize_rigid_object_friction",
    "randomize_joint_damping",
    "randomize_joint_stiffness",
    "randomize_joint_drive",
]

_OBJECTS = (RigidObject, RigidObjectGroup)


def _masses(env: Any, ids: Any, bodies: list[int], sample: np.ndarray, relative: bool) -> None:
    """Set body masses (n, k) (relative: added to the configured ones), inertias scaled along."""
    index = np.asarray(bodies, dtype=np.int64)
    mass = sample + env.scene.model.body_mass[index][None, :] if relative else sample
    env.sim.set_body_masses(ids, index, np.maximum(mass, 1e-6))


def _check_mass(env: Any, entity_cfg: SceneEntityCfg, mass_range: Any, relative: bool = False) -> None:
    entity_of(env, entity_cfg, "randomize_rigid_object_mass", _OBJECTS)
    low, _ = as_range(mass_range, "randomize_rigid_object_mass", "mass_range")
    if not relative and (low <= 0).any():
        raise ParamError(
            "randomize_rigid_object_mass", "mass_range", f"absolute masses must be > 0, got {mass_range!r}"
        )


@validated(_check_mass)
def randomize_rigid_object_mass(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, mass_range: Any, relative: bool = False
) -> None:
    """Draw a mass per env for a rigid object (or every member of a group).

    The inertia scales with the mass, so the density distribution is kept.

    Args:
        env: the env.
        env_ids: envs to randomize (``None``: all).
        entity_cfg: the rigid object or group.
        mass_range: ``[low, high]`` in kg.
        relative: add the draw to the configured mass instead of replacing it
            (the result is clamped to stay positive).

    Example:
        ``{"func": "randomize_rigid_object_mass", "mode": "reset",
        "params": {"entity_cfg": {"uid": "fork"}, "mass_range": [0.1, 2.0]}}``
    """
    ids = env_ids_of(env, env_ids)
    low, high = as_range(mass_range, "randomize_rigid_object_mass", "mass_range")
    bodies = [obj.body_id for obj in rigid_bodies(env.scene[entity_cfg.uid])]
    sample = np.repeat(uniform_np(env, ids, low, high)[:, None], len(bodies), axis=1)
    _masses(env, ids, bodies, sample, relative)


class randomize_rigid_object_center_of_mass(CheckedFunctor):
    """Offset the centre of mass of a dynamic rigid object per env (body frame, metres).

    The offset is added to the configured centre of mass, so repeated calls do not
    drift. The body is compiled with a general inertial frame (``modify_scene``)
    so its centre of mass may move. Kinematic and static objects are skipped with
    a warning.

    Args (params):
        entity_cfg: the rigid object (or group).
        com_pos_offset_range: ``[[dx, dy, dz] low, [dx, dy, dz] high]``.

    Example:
        ``{"func": "randomize_rigid_object_center_of_mass", "mode": "reset", "params":
        {"entity_cfg": {"uid": "cube"}, "com_pos_offset_range": [[-0.01, -0.01, 0], [0.01, 0.01, 0]]}}``
    """

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Let the object's bodies change their inertial frame per env."""
        entity = cfg.params.get("entity_cfg")
        uid = entity["uid"] if isinstance(entity, dict) else getattr(entity, "uid", None)
        record = scene.builder.records.get(uid)
        if record is None:
            return
        names = [m.uid for _, m in record.extra["members"]] if record.kind == "group" else [uid]
        for name in names:
            body = scene.builder.spec.body(name)
            if body is not None:
                body.simple = False

    def check(self, env: Any, entity_cfg: Any = None, com_pos_offset_range: Any = None) -> None:
        entity_of(env, entity_cfg, type(self).__name__, _OBJECTS)
        as_range(com_pos_offset_range, type(self).__name__, "com_pos_offset_range", width=3)

    def __call__(self, env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, com_pos_offset_range: Any) -> None:
        ids = env_ids_of(env, env_ids)
        low, high = as_range(com_pos_offset_range, type(self).__name__, "com_pos_offset_range", 3)
        bodies = [o.body_id for o in rigid_bodies(env.scene[entity_cfg.uid]) if o.is_dynamic]
        if not bodies:
            warnings.warn(
                f"{type(self).__name__}: {entity_cfg.uid!r} is not dynamic; skipped", RuntimeWarning, stacklevel=2
            )
            return
        offset = uniform_np(env, ids, low, high, (len(bodies),))
        com = env.scene.model.body_ipos[bodies][None] + offset
        write_model(env.sim, ids, [("body_ipos", bodies, com)])


def _link_ranges(art: Articulation, mass_range: Any, link_names: Any) -> list[tuple[list[int], Any]]:
    """``[(body ids, [low, high])]`` of a tuple range or a ``{link regex: range}`` dict."""
    if not isinstance(mass_range, dict):
        return [(link_body_ids(art, link_names)[0], mass_range)]
    out = []
    for pattern, rng in mass_range.items():
        try:
            out.append((link_body_ids(art, pattern)[0], rng))
        except KeyError as err:
            raise ParamError("randomize_articulation_mass", "mass_range", str(err).strip("\"'")) from None
    return out


def _check_art_mass(
    env: Any, entity_cfg: SceneEntityCfg, mass_range: Any, link_names: Any = None, relative: bool = False
) -> None:
    name = "randomize_articulation_mass"
    art = entity_of(env, entity_cfg, name, (Articulation,))
    try:
        groups = _link_ranges(art, mass_range, link_names)
    except KeyError as err:
        raise ParamError(name, "link_names", str(err).strip("\"'")) from None
    for _, rng in groups:
        low, _ = as_range(rng, name, "mass_range")
        if not relative and (low <= 0).any():
            raise ParamError(name, "mass_range", f"absolute masses must be > 0, got {rng!r}")


@validated(_check_art_mass)
def randomize_articulation_mass(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    mass_range: Union[list, tuple, dict],
    link_names: Optional[Any] = None,
    relative: bool = False,
) -> None:
    """Draw link masses per env and per link for an articulation or robot.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the articulation.
        mass_range: ``[low, high]`` for every selected link, or ``{link regex: [low, high]}``
            (then ``link_names`` is ignored; an unknown link is an error).
        link_names: link regexes (all links when ``None``).
        relative: add the draw to each link's configured mass.

    Example:
        ``{"func": "randomize_articulation_mass", "mode": "reset", "params": {"entity_cfg":
        {"uid": "drawer"}, "mass_range": [0.5, 2.0], "link_names": ["inner_.*"]}}``
    """
    ids = env_ids_of(env, env_ids)
    art = env.scene[entity_cfg.uid]
    for bodies, rng in _link_ranges(art, mass_range, link_names):
        low, high = as_range(rng, "randomize_articulation_mass", "mass_range")
        sample = uniform_np(env, ids, low, high, (len(bodies),))
        _masses(env, ids, bodies, sample, relative)


def _check_friction(env: Any, entity_cfg: SceneEntityCfg, friction_range: Any, relative: bool = False) -> None:
    entity_of(env, entity_cfg, "randomize_rigid_object_friction", _OBJECTS)
    low, _ = as_range(friction_range, "randomize_rigid_object_friction", "friction_range")
    if not relative and (low < 0).any():
        raise ParamError("randomize_rigid_object_friction", "friction_range", "friction must be >= 0")


@validated(_check_friction)
def randomize_rigid_object_friction(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, friction_range: Any, relative: bool = False
) -> None:
    """Draw the sliding friction coefficient of a rigid object's collision geoms per env.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the rigid object (or group).
        friction_range: ``[low, high]`` (MuJoCo sliding friction, PhysX static friction).
        relative: add the draw to the configured friction (clamped at 0).

    Example:
        ``{"func": "randomize_rigid_object_friction", "mode": "reset",
        "params": {"entity_cfg": {"uid": "cube"}, "friction_range": [0.3, 1.2]}}``
    """
    ids = env_ids_of(env, env_ids)
    low, high = as_range(friction_range, "randomize_rigid_object_friction", "friction_range")
    value = uniform_np(env, ids, low, high).reshape(len(ids))
    writes = []
    for obj in rigid_bodies(env.scene[entity_cfg.uid]):
        for gid in obj.geom_ids:
            base = env.scene.model.geom_friction[gid, 0] if relative else 0.0
            writes.append(("geom_friction", (gid, 0), np.maximum(base + value, 0.0)))
    write_model(env.sim, ids, writes)
