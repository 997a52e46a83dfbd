"""Per-env mesh variants of a rigid object (e.g. a different fork in each env).

Every variant is compiled once into the one scene model: the object's body holds
the visual and collision geoms of all its variants, and each env enables one
variant through per-env model fields (collision bits, visual material, and the
body's inertial properties). All envs keep one model and one MjData layout, so
switching meshes on reset is a few array writes, never a recompile.

Why not one compiled model per variant (``Batch.set_models``)? MuJoCo sizes
MjData by the meshes' BVHs and by the sparsity of the mass matrix, which differ
between meshes, and a batch needs one layout.

Example:
    >>> scene.reserve_mesh_variants("fork", ["a.ply", "b.ply"])   # before build
    >>> scene.build()
    >>> scene.set_mesh_variant("fork", "b.ply", env_ids=[0, 2])  # any time after
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from embodichain_core.sim.builder import VISUAL_GROUP

ALL_BITS = (1 << 30) - 1
PARKED = 1 << 30  # collides with nothing, but compiled as a colliding geom
HIDDEN_MATERIAL = "embodichain/hidden"


def load_variant_parts(cfg: Any, fpath: str) -> tuple[Any, list]:
    """Visual mesh and collision parts of ``fpath`` with ``cfg``'s scale and options."""
    from embodichain_core.sim.convex import collision_parts
    from embodichain_core.sim.mesh import load_mesh

    shape = cfg.shape
    mesh = load_mesh(fpath, scale=tuple(cfg.body_scale), compute_uv=shape.compute_uv,
                     project_direction=tuple(shape.project_direction))
    hulls = cfg.max_convex_hull_num if cfg.max_convex_hull_num is not None else shape.max_convex_hull_num
    return mesh, collision_parts(mesh, max_convex_hull_num=int(hulls))


def add_variants(builder: Any, uid: str, files: list[str]) -> None:
    """Add the geoms of every file in ``files`` (disabled) to ``uid``'s body."""
    from embodichain_core.sim.builder_objects import add_collision_geoms, add_mesh_asset

    record = builder.record(uid)
    cfg = record.cfg
    variants = record.extra.setdefault("variants", {})
    if not variants:
        variants[record.extra["mesh_file"]] = {
            "visual": list(record.extra["visual_geoms"]), "collision": list(record.extra["collision_geoms"])}
    _hidden_material(builder.spec)
    body = builder.spec.body(uid)
    body.simple = False  # the inertial frame changes per env: keep a general mass matrix
    for k, fpath in enumerate(f for f in files if f not in variants):
        name = f"{uid}/v{len(variants)}"
        mesh, parts = load_variant_parts(cfg, fpath)
        asset = add_mesh_asset(builder.spec, f"{name}/visual", mesh)
        vgeom = body.add_geom(name=f"{name}/visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=asset,
                              material=HIDDEN_MATERIAL, rgba=[0, 0, 0, 0])
        vgeom.contype = vgeom.conaffinity = 0
        vgeom.group, vgeom.density = VISUAL_GROUP, 0.0
        collision = add_collision_geoms(builder.spec, body, name, parts, cfg)
        for gname in collision:
            geom = builder.spec.geom(gname)
            geom.contype, geom.conaffinity = PARKED, 0
            geom.mass, geom.density = 0.0, 0.0
        variants[fpath] = {"visual": [vgeom.name], "collision": collision, "parts": parts}
    builder.on_compile(lambda model: _inertials(builder, uid, model))


def _hidden_material(spec: mujoco.MjSpec) -> None:
    if not any(m.name == HIDDEN_MATERIAL for m in spec.materials):
        spec.add_material(name=HIDDEN_MATERIAL, rgba=[0, 0, 0, 0])


def _inertials(builder: Any, uid: str, model: mujoco.MjModel) -> None:
    """Each variant's mass, centre of mass and inertia, as MuJoCo computes them."""
    from embodichain_core.sim.builder_objects import add_collision_geoms

    record = builder.record(uid)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, uid)
    for fpath, variant in record.extra["variants"].items():
        if "parts" not in variant:
            variant["inertial"] = tuple(np.array(getattr(model, f)[base]) for f in _INERTIAL)
            continue
        spec = mujoco.MjSpec()
        body = spec.worldbody.add_body(name="b")
        body.add_freejoint()
        add_collision_geoms(spec, body, "b", variant["parts"], record.cfg)
        small = spec.compile()
        variant["inertial"] = tuple(np.array(getattr(small, f)[1]) for f in _INERTIAL)


_INERTIAL = ("body_mass", "body_ipos", "body_iquat", "body_inertia")


def apply_variant(scene: Any, uid: str, fpath: str, env_ids: Any) -> None:
    """Enable ``fpath``'s geoms (and inertia) for ``env_ids``; disable the others."""
    record = scene.builder.record(uid)
    variants = record.extra.get("variants", {})
    if fpath not in variants:
        raise ValueError(f"{uid}: {fpath!r} was not reserved; call scene.reserve_mesh_variants({uid!r}, files) "
                         f"before build (reserved: {list(variants)})")
    model, sim = scene.model, scene.sim
    ids = lambda names: [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n) for n in names]
    mat = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, record.extra["material"])
    hidden = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, HIDDEN_MATERIAL)
    for name, variant in variants.items():
        on = name == fpath
        for g in ids(variant["collision"]):
            sim.set_model_field("geom_contype", env_ids, g, 1 if on else PARKED)
            sim.set_model_field("geom_conaffinity", env_ids, g, ALL_BITS if on else 0)
        for g in ids(variant["visual"]):
            sim.set_model_field("geom_matid", env_ids, g, mat if on else hidden)
            # MuJoCo's default geom rgba lets the material's colour show
            sim.set_model_field("geom_rgba", env_ids, g, [0.5, 0.5, 0.5, 1] if on else [0, 0, 0, 0])
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, uid)
    for field, value in zip(_INERTIAL, variants[fpath]["inertial"]):
        sim.set_model_field(field, env_ids, body, value)
