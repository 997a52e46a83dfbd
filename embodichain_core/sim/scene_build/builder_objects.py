"""Rigid objects, backgrounds and rigid-object groups on the scene spec."""

from __future__ import annotations

import functools
import os
from typing import Any

import mujoco
import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.scene_build.builder_articulation import ALL_COLLISION_BITS
from embodichain_core.sim.scene_build.builder import COLLISION_GROUP, VISUAL_GROUP, EntityRecord, SceneBuilder
from embodichain_core.sim.cfg import RigidObjectCfg, RigidObjectGroupCfg
from embodichain_core.sim.shapes import CapsuleCfg, CubeCfg, CylinderCfg, MeshCfg, SphereCfg
from embodichain_core.utils.math import init_pos_from_cfg, init_quat_from_cfg

_PRIMITIVES = {
    CubeCfg: mujoco.mjtGeom.mjGEOM_BOX,
    SphereCfg: mujoco.mjtGeom.mjGEOM_SPHERE,
    CylinderCfg: mujoco.mjtGeom.mjGEOM_CYLINDER,
    CapsuleCfg: mujoco.mjtGeom.mjGEOM_CAPSULE,
}


def add_rigid_object(builder: SceneBuilder, cfg: RigidObjectCfg, role: str, path: str) -> EntityRecord:
    """Add a rigid object (``role`` is ``rigid_object`` or ``background``).

    Dynamic objects get a free joint; kinematic and static ones are mocap bodies,
    so each env can move them without recompiling.
    """
    _check_body_type(cfg, role, path)
    record = builder.claim_uid(cfg.uid, role, cfg, path)
    uid = record.uid  # cfg.uid, checked to be a non-empty string
    body = _add_body(builder, cfg, name=uid)
    parts = _add_shape(builder, body, cfg, name=uid, path=path)
    record.root_body = uid
    record.extra.update(parts)
    if cfg.body_type == "dynamic":
        builder.on_compile(functools.partial(_apply_damping, uid=uid, cfg=cfg))
    return record


def add_rigid_object_group(builder: SceneBuilder, cfg: RigidObjectGroupCfg, path: str) -> EntityRecord:
    """Add every member of a group as a body named ``<group uid>/<member>``."""
    members = _group_members(cfg, path)
    record = builder.claim_uid(cfg.uid, "group", cfg, path)
    record.extra["members"], record.extra["parts"] = [], {}
    for name, member in members.items():
        uid = f"{cfg.uid}/{name}"
        member = member.replace(uid=uid, body_type=cfg.body_type)
        body = _add_body(builder, member, name=uid)
        parts = _add_shape(builder, body, member, name=uid, path=f"{path}.rigid_objects.{name}")
        record.extra["parts"][uid] = parts
        record.extra["members"].append((name, member))
        if member.body_type == "dynamic":
            builder.on_compile(functools.partial(_apply_damping, uid=uid, cfg=member))
    return record


def _group_members(cfg: RigidObjectGroupCfg, path: str) -> dict[str, RigidObjectCfg]:
    if not cfg.folder_path:
        if not cfg.rigid_objects:
            raise ConfigError(f"{path}.rigid_objects", f"group {cfg.uid!r} has no rigid_objects and no folder_path")
        return dict(cfg.rigid_objects)
    from embodichain_core.sim.data import get_data_path

    folder = get_data_path(cfg.folder_path)
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith(cfg.ext.lower()))
    if not files:
        raise ConfigError(f"{path}.folder_path", f"no '*{cfg.ext}' files in {folder}")
    if not cfg.rigid_objects:
        raise ConfigError(f"{path}.rigid_objects", "template mode needs one rigid_objects entry as the template")
    template = next(iter(cfg.rigid_objects.values()))
    out = {}
    for i in range(int(cfg.max_num)):
        shape = MeshCfg(fpath=os.path.join(folder, files[i % len(files)]))
        out[f"{cfg.uid}_obj_{i}"] = template.replace(shape=shape)
    return out


def _check_body_type(cfg: RigidObjectCfg, role: str, path: str) -> None:
    if role == "background" and cfg.body_type == "dynamic":
        raise ConfigError(
            f"{path}.body_type",
            f"background {cfg.uid!r} is 'dynamic'; backgrounds must be 'kinematic' or 'static' "
            "(move it to rigid_object to simulate it)",
        )
    if role == "rigid_object" and cfg.body_type != "dynamic":
        raise ConfigError(
            f"{path}.body_type",
            f"rigid_object {cfg.uid!r} is {cfg.body_type!r}; rigid objects must be 'dynamic' "
            "(put kinematic or static objects under background)",
        )


def _add_body(builder: SceneBuilder, cfg: RigidObjectCfg, name: str) -> Any:
    builder.require_iterations(cfg.attrs)
    body = builder.spec.worldbody.add_body(name=name)
    body.pos = init_pos_from_cfg(cfg.init_pos, cfg.init_local_pose)
    body.quat = init_quat_from_cfg(cfg.init_rot, cfg.init_local_pose)
    if cfg.body_type == "dynamic":
        body.add_freejoint(name=f"{name}/free")
        builder.sleep_policy(body, cfg.attrs.sleep_threshold)
    else:
        body.mocap = True
    return body


def _geom_common(geom: Any, cfg: RigidObjectCfg) -> None:
    attrs = cfg.attrs
    geom.friction = [float(attrs.static_friction), 0.005, 0.0001]
    geom.contype, geom.conaffinity = 1, ALL_COLLISION_BITS
    # MuJoCo rests contacts at the sum of the two margins, so only PhysX's
    # rest_offset (default 0) maps onto margin; contact_offset has no MuJoCo twin
    geom.margin = float(attrs.rest_offset)
    geom.gap = 0.0
    if not attrs.enable_collision:
        geom.contype = geom.conaffinity = 0


def _material(builder: SceneBuilder, cfg: RigidObjectCfg, name: str) -> str:
    """Every object gets its own material ``<uid>/mat`` so it can be recoloured per env."""
    vm = cfg.shape.visual_material
    mat = builder.spec.add_material(name=f"{name}/mat")
    mat.rgba = list(vm.base_color) if vm is not None else [0.7, 0.7, 0.7, 1.0]
    if vm is not None:
        mat.metallic, mat.roughness = float(vm.metallic), float(vm.roughness)
        if vm.base_color_texture:
            from embodichain_core.sim.data import get_data_path

            tex = builder.spec.add_texture(name=f"{name}/tex", type=mujoco.mjtTexture.mjTEXTURE_2D)
            tex.file = get_data_path(vm.base_color_texture)
            mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = f"{name}/tex"
    return f"{name}/mat"


def _add_shape(builder: SceneBuilder, body: Any, cfg: RigidObjectCfg, name: str, path: str) -> dict:
    scale = np.asarray(cfg.body_scale, dtype=float)
    material = _material(builder, cfg, name)
    shape = cfg.shape
    if isinstance(shape, MeshCfg):
        return _add_mesh_shape(builder, body, cfg, shape, name, scale, material, path)
    gtype = _PRIMITIVES.get(type(shape))
    if gtype is None:
        raise ConfigError(f"{path}.shape", f"unsupported shape {type(shape).__name__}")
    geom = body.add_geom(name=f"{name}/geom", type=gtype, material=material)
    geom.size = _primitive_size(shape, scale)
    _geom_common(geom, cfg)
    if cfg.attrs.mass > 0:
        geom.mass = float(cfg.attrs.mass)
    else:
        geom.density = float(cfg.attrs.density)
    return {"visual_geoms": [geom.name], "collision_geoms": [geom.name], "material": material}


def _primitive_size(shape: Any, scale: np.ndarray) -> list[float]:
    if isinstance(shape, CubeCfg):
        return list(np.asarray(shape.size, dtype=float) * 0.5 * scale)
    if isinstance(shape, SphereCfg):
        return [float(shape.radius) * float(scale.max()), 0.0, 0.0]
    return [float(shape.radius) * float(max(scale[0], scale[1])), float(shape.height) * 0.5 * float(scale[2]), 0.0]


def _add_mesh_shape(builder, body, cfg, shape, name, scale, material, path) -> dict:
    from embodichain_core.sim.scene_build.convex import collision_parts
    from embodichain_core.sim.data import get_data_path
    from embodichain_core.sim.scene_build.mesh import load_mesh

    try:
        fpath = get_data_path(shape.fpath)
    except FileNotFoundError as err:
        raise ConfigError(f"{path}.shape.fpath", str(err)) from err
    mesh = load_mesh(
        fpath, scale=tuple(scale), compute_uv=shape.compute_uv, project_direction=tuple(shape.project_direction)
    )
    hulls = cfg.max_convex_hull_num if cfg.max_convex_hull_num is not None else shape.max_convex_hull_num
    parts = collision_parts(mesh, max_convex_hull_num=int(hulls))
    visual = add_mesh_asset(builder.spec, f"{name}/visual", mesh)
    vgeom = body.add_geom(name=f"{name}/visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=visual, material=material)
    vgeom.contype = vgeom.conaffinity = 0
    vgeom.group, vgeom.density = VISUAL_GROUP, 0.0
    names = add_collision_geoms(builder.spec, body, name, parts, cfg)
    return {"visual_geoms": [vgeom.name], "collision_geoms": names, "material": material, "mesh_file": fpath}


def add_mesh_asset(spec: mujoco.MjSpec, name: str, mesh: Any) -> str:
    """Add a mesh asset from vertices/faces (and texture coordinates when present)."""
    asset = spec.add_mesh(name=name)
    asset.uservert = np.asarray(mesh.vertices, dtype=np.float32).reshape(-1).tolist()
    asset.userface = np.asarray(mesh.faces, dtype=np.int32).reshape(-1).tolist()
    if getattr(mesh, "texcoords", None) is not None:
        asset.usertexcoord = np.asarray(mesh.texcoords, dtype=np.float32).reshape(-1).tolist()
    asset.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
    return name


def add_collision_geoms(spec: mujoco.MjSpec, body: Any, name: str, parts: list, cfg: RigidObjectCfg) -> list[str]:
    """One convex mesh geom per part, masses split by part volume."""
    volumes = np.array([max(_volume(p), 1e-9) for p in parts])
    names = []
    for i, part in enumerate(parts):
        asset = spec.add_mesh(name=f"{name}/collision_{i}")
        asset.uservert = np.asarray(part.vertices, dtype=np.float32).reshape(-1).tolist()
        asset.userface = np.asarray(part.faces, dtype=np.int32).reshape(-1).tolist()
        asset.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX
        geom = body.add_geom(name=f"{name}/collision_{i}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=asset.name)
        geom.group, geom.rgba = COLLISION_GROUP, [0.5, 0.5, 0.9, 0.4]
        _geom_common(geom, cfg)
        if cfg.attrs.mass > 0:
            geom.mass = float(cfg.attrs.mass * volumes[i] / volumes.sum())
        else:
            geom.density = float(cfg.attrs.density)
        names.append(geom.name)
    return names


def _volume(mesh: Any) -> float:
    v = np.asarray(mesh.vertices, dtype=float)
    f = np.asarray(mesh.faces, dtype=int)
    if len(f) == 0:
        return 0.0
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0)


def _apply_damping(model: mujoco.MjModel, uid: str, cfg: RigidObjectCfg) -> None:
    """PhysX-style linear/angular damping (1/s) as free-joint dof damping."""
    jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{uid}/free")
    if jid < 0:
        return
    dof = model.jnt_dofadr[jid]
    body = model.jnt_bodyid[jid]
    model.dof_damping[dof : dof + 3] = cfg.attrs.linear_damping * model.body_mass[body]
    model.dof_damping[dof + 3 : dof + 6] = cfg.attrs.angular_damping * model.body_inertia[body]
