"""Asset events: per-env mesh swaps from a folder, detached reset uids, dropping a group."""

from __future__ import annotations

import fnmatch
import os
from typing import Any, Sequence

import mujoco
import torch

from embodichain_core.managers import DataPath, SceneEntityCfg
from embodichain_core.sim.data import get_data_path
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.scene_build.mesh import MESH_SUFFIXES

from embodichain_functors._common import (
    ParamError,
    as_range,
    check_positive,
    entity_of,
    env_ids_of,
    randint,
    uniform,
    validated,
)
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._sim import step_envs, write_model

__all__ = [
    "replace_assets_from_group",
    "set_detached_uids_for_env_reset",
    "drop_rigid_object_group_sequentially",
    "mesh_files",
]

_USE_MATERIAL_RGBA = [0.5, 0.5, 0.5, 1.0]


def mesh_files(folder_path: str, functor: str = "replace_assets_from_group") -> list[str]:
    """Mesh files of a folder (asset name or path), sorted; a last component with
    wildcards (``fork/*_scale.ply``) filters the file names. Non-mesh files are skipped."""
    if not isinstance(folder_path, str) or not folder_path:
        raise ParamError(functor, "folder_path", f"must be a folder (asset name or path), got {folder_path!r}")
    folder, pattern = folder_path, "*"
    if any(c in os.path.basename(folder_path.rstrip("/")) for c in "*?["):
        folder, pattern = os.path.dirname(folder_path.rstrip("/")), os.path.basename(folder_path.rstrip("/"))
    try:
        folder = get_data_path(folder)
    except FileNotFoundError as err:
        raise ParamError(functor, "folder_path", str(err).splitlines()[0]) from None
    if not os.path.isdir(folder):
        raise ParamError(functor, "folder_path", f"{folder!r} is not a folder")
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith(MESH_SUFFIXES) and fnmatch.fnmatch(f, pattern))
    if not files:
        raise ParamError(functor, "folder_path", f"no mesh files ({', '.join(MESH_SUFFIXES)}) in {folder_path!r}")
    return [os.path.join(folder, f) for f in files]


class replace_assets_from_group(CheckedFunctor):
    """Give each env a random mesh from a folder for a mesh rigid object, on every call.

    Every mesh of the folder is compiled into the model once (``modify_scene``
    reserves them as mesh variants before the scene compiles); a call then only
    switches which variant each env in ``env_ids`` simulates and renders. The
    object keeps its pose, material and configured scale; mass and inertia are
    the chosen mesh's. ``env.scene.current_mesh[uid]`` lists each env's file.

    Args (params):
        entity_cfg: the mesh rigid object (dynamic, kinematic or static).
        folder_path: folder of meshes (asset name or path); a last component with
            wildcards filters the file names (``"TableWare/tableware/fork/*.ply"``).

    Example:
        ``{"func": "replace_assets_from_group", "mode": "reset", "params": {"entity_cfg": {"uid": "fork"},
        "folder_path": "TableWare/tableware/fork/"}}``
    """

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Reserve every mesh of ``folder_path`` as a variant of the object."""
        entity = cfg.params["entity_cfg"]
        uid = entity["uid"] if isinstance(entity, dict) else entity.uid
        scene.reserve_mesh_variants(uid, mesh_files(cfg.params["folder_path"], cls.__name__))

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.files = mesh_files(cfg.params["folder_path"], type(self).__name__)
        uid = cfg.params["entity_cfg"].uid
        variants = env.scene.builder.record(uid).extra.get("variants", {})
        model = env.scene.model
        self._visual = {
            f: [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in v["visual"]] for f, v in variants.items()
        }

    def check(self, env: Any, entity_cfg: Any = None, folder_path: Any = None) -> None:
        from embodichain_core.sim.entities.rigid_object import RigidObject

        entity_of(env, entity_cfg, type(self).__name__, (RigidObject,))
        if not isinstance(folder_path, str):
            raise ParamError(type(self).__name__, "folder_path", f"must be a string, got {folder_path!r}")
        mesh_files(folder_path, type(self).__name__)

    def __call__(self, env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, folder_path: DataPath) -> None:
        ids = env_ids_of(env, env_ids)
        pick = randint(env, ids, len(self.files))
        for k, path in enumerate(self.files):
            chosen = ids[pick == k]
            if len(chosen):
                env.scene.set_mesh_variant(entity_cfg.uid, path, chosen)
                # show the object's material colour (the core writes an opaque white geom rgba)
                write_model(env.sim, chosen, [("geom_rgba", self._visual.get(path, []), _USE_MATERIAL_RGBA)])


def _check_detached(env: Any, uids: Any) -> None:
    names = [uids] if isinstance(uids, str) else list(uids)
    missing = [u for u in names if u not in env.scene]
    if missing:
        raise ParamError("set_detached_uids_for_env_reset", "uids", f"no entities {missing} in the scene")


@validated(_check_detached)
def set_detached_uids_for_env_reset(env: Any, env_ids: Any, uids: Any) -> None:
    """Exclude entities from the automatic reset to their initial state (typically at startup).

    Args:
        env: the env.
        env_ids: unused (the setting is global).
        uids: a uid or a list of uids.

    Example:
        ``{"func": "set_detached_uids_for_env_reset", "mode": "startup", "params": {"uids": ["table"]}}``
    """
    names = [uids] if isinstance(uids, str) else list(uids)
    already = getattr(env, "_detached_uids_for_reset", [])  # adding twice would grow the list every reset
    env.add_detached_uids_for_reset([u for u in names if u not in already])


def _check_drop(
    env: Any,
    entity_cfg: SceneEntityCfg,
    drop_position: Sequence[float] = (0.0, 0.0, 1.0),
    position_range: Any = None,
    physics_step: int = 2,
) -> None:
    name = "drop_rigid_object_group_sequentially"
    entity_of(env, entity_cfg, name, (RigidObjectGroup,))
    if len(drop_position) != 3:
        raise ParamError(name, "drop_position", f"needs 3 values, got {drop_position!r}")
    if position_range is not None:
        as_range(position_range, name, "position_range", 3)
    check_positive(physics_step, name, "physics_step", allow_zero=True)


@validated(_check_drop)
def drop_rigid_object_group_sequentially(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    drop_position: Sequence[float] = (0.0, 0.0, 1.0),
    position_range: Any = ((-0.1, -0.1, 0.0), (0.1, 0.1, 0.0)),
    physics_step: int = 2,
) -> None:
    """Drop the members of a group one by one at a random point around ``drop_position``.

    Each member is placed (keeping its orientation, velocities cleared), then only
    these envs are simulated ``physics_step`` steps before the next one.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the rigid-object group.
        drop_position: ``[x, y, z]`` drop point in the env frame.
        position_range: ``[[dx, dy, dz] low, [...] high]`` random offset of each drop.
        physics_step: physics steps after each drop.

    Example:
        ``{"func": "drop_rigid_object_group_sequentially", "mode": "reset", "params": {"entity_cfg":
        {"uid": "blocks"}, "drop_position": [0.5, 0, 0.3], "physics_step": 5}}``
    """
    ids = env_ids_of(env, env_ids)
    group = env.scene[entity_cfg.uid]
    low, high = as_range(position_range, "drop_rigid_object_group_sequentially", "position_range", 3)
    for member in group.members:
        pose = member.get_local_pose()[ids].to(torch.float64)
        pose[:, :3] = torch.as_tensor(drop_position, dtype=torch.float64) + uniform(env, ids, low, high)
        member.set_local_pose(pose, ids)
        member.clear_dynamics(ids)
        step_envs(env, ids, int(physics_step))
