"""Entity lookups shared by the functors (rigid objects, groups, articulations, joints)."""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject


def rigid_bodies(entity: Any) -> list[RigidObject]:
    """The rigid objects of a rigid object (itself) or of a group (its members)."""
    if isinstance(entity, RigidObjectGroup):
        return list(entity.members)
    return [entity]


def joint_ids_of(articulation: Articulation, entity_cfg: Any) -> list[int]:
    """Joint ids selected by a resolved ``SceneEntityCfg`` (every joint by default)."""
    ids = getattr(entity_cfg, "joint_ids", slice(None))
    if isinstance(ids, slice):
        return list(range(articulation.dof))[ids]
    return [int(i) for i in (ids.tolist() if isinstance(ids, torch.Tensor) else ids)]


def mj_joint_ids(articulation: Articulation, joint_ids: list[int]) -> list[int]:
    """MuJoCo joint ids of articulation joints ``joint_ids``."""
    return articulation.scene.model.dof_jntid[articulation.dof_adr.numpy()[joint_ids]].tolist()


def link_body_ids(articulation: Articulation, link_names: Any) -> tuple[list[int], list[str]]:
    """MuJoCo body ids and names of the links matching ``link_names`` (all when ``None``)."""
    if link_names is None:
        return [int(b) for b in articulation.body_ids], list(articulation.link_names)
    ids, names = articulation.find_bodies(link_names, preserve_order=True)
    return [int(articulation.body_ids[i]) for i in ids], names


def all_uids(env: Any, group: str) -> list[str]:
    """Scene uids of a group: ``all_objects``, ``all_robots``, ``all_sensors``, ``all_lights``..."""
    scene = env.scene
    groups = {
        "all_objects": list(scene.rigid_objects) + list(scene.articulations),
        "all_rigid_objects": list(scene.rigid_objects),
        "all_backgrounds": list(scene.backgrounds),
        "all_articulations": list(scene.articulations),
        "all_robots": list(scene.robots),
        "all_sensors": list(scene.sensors),
        "all_lights": list(scene.lights),
        "all_groups": list(scene.groups),
    }
    return groups[group] if group in groups else [group]


def resolve_uids(env: Any, entity_uids: Any) -> list[str]:
    """Expand ``"all_objects"`` / ``"all_robots"`` / ``"all_sensors"`` or one uid into uids."""
    if isinstance(entity_uids, str):
        return all_uids(env, entity_uids)
    out: list[str] = []
    for uid in entity_uids:
        out += [u for u in all_uids(env, uid) if u not in out]
    return out
