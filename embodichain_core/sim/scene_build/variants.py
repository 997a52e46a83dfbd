"""Per-env mesh variants of a rigid object (e.g. a different fork in each env).

Every variant is compiled once into the one scene model: the object's body holds
the visual and collision geoms of all its variants, and each env enables one
variant through per-env model fields (collision bits, visual material, and the
body's inertial properties). All envs keep one model and one MjData layout, so
switching meshes on reset is a few array writes, never a recompile.

Why not one compiled model per variant (``Batch.set_models``)? MuJoCo sizes
MjData by the meshes' BVHs and by the sparsity of the mass matrix, which differ
between meshes, and a batch needs one layout.

A variant is another mesh file or the object's own mesh scaled by a factor (a mesh
cannot be rescaled per env otherwise: its vertices are shared by every env). A
scaled variant keeps the object's mass; its inertia and centre of mass follow the
scaled shape.

Example:
    >>> scene.reserve_mesh_variants("fork", ["a.ply", "b.ply"])   # before build
    >>> keys = scene.reserve_scale_variants("mug", [(0.8, 0.8, 0.8), (1.2, 1.2, 1.2)])
    >>> scene.build()
    >>> scene.set_mesh_variant("fork", "b.ply", env_ids=[0, 2])  # any time after
    >>> scene.set_mesh_variants("mug", [keys[0], keys[1]], env_ids=[0, 1])  # one per env
"""

from __future__ import annotations

import dataclasses
from typing import Any, Optional, Sequence

import mujoco
import numpy as np

from embodichain_core.sim.scene_build.builder import VISUAL_GROUP

ALL_BITS = (1 << 30) - 1
PARKED = 1 << 30  # collides with nothing, but compiled as a colliding geom
HIDDEN_MATERIAL = "embodichain/hidden"
#: Backend ``warp`` cannot switch collision bits per env (MuJoCo Warp fixes the colliding geom
#: pairs for every world): it parks the unused variants' geoms this high above their body
#: (plus ``PARK_SPACING`` per object with variants, so that two objects' parked geoms never meet).
PARK_HEIGHT = 100.0
PARK_SPACING = 10.0


def parks_variants(builder: Any) -> bool:
    """Whether the scene switches variants by parking geoms (backend ``warp``)."""
    return getattr(getattr(builder, "sim_cfg", None), "backend", "mujoco_batch") == "warp"


def variant_fields(builder: Any) -> tuple[str, ...]:
    """The per-env model fields that switch collision geoms between variants."""
    return ("geom_pos",) if parks_variants(builder) else ("geom_contype", "geom_conaffinity")


def load_variant_parts(cfg: Any, fpath: str, factor: Optional[Sequence[float]] = None) -> tuple[Any, list]:
    """Visual mesh and collision parts of ``fpath`` with ``cfg``'s scale and options,
    times ``factor`` (the parts are scaled, not decomposed again)."""
    from embodichain_core.sim.scene_build.convex import collision_parts
    from embodichain_core.sim.scene_build.mesh import load_mesh

    shape = cfg.shape
    mesh = load_mesh(
        fpath,
        scale=tuple(cfg.body_scale),
        compute_uv=shape.compute_uv,
        project_direction=tuple(shape.project_direction),
    )
    hulls = cfg.max_convex_hull_num if cfg.max_convex_hull_num is not None else shape.max_convex_hull_num
    parts = collision_parts(mesh, max_convex_hull_num=int(hulls))
    if factor is None:
        return mesh, parts
    return _scaled(mesh, factor), [_scaled(p, factor) for p in parts]


def _scaled(mesh: Any, factor: Sequence[float]) -> Any:
    f = np.asarray(factor, dtype=np.float64)
    normals = None if mesh.normals is None else mesh.normals / f
    if normals is not None:
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    return dataclasses.replace(mesh, vertices=mesh.vertices * f, normals=normals)


def scale_key(factor: Sequence[float]) -> str:
    """The variant key of the object's own mesh scaled by ``factor``."""
    return "scale:" + "x".join(f"{float(v):.6g}" for v in factor)


def add_variants(
    builder: Any, uid: str, files: list[str], factors: Optional[list[Sequence[float]]] = None
) -> list[str]:
    """Add the geoms of every file in ``files`` (or of the object's mesh scaled by each of
    ``factors``) to ``uid``'s body, disabled; return their keys."""
    from embodichain_core.sim.scene_build.builder_objects import add_collision_geoms, add_mesh_asset

    record = builder.record(uid)
    cfg = record.cfg
    variants = record.extra.setdefault("variants", {})
    if not variants:
        variants[record.extra["mesh_file"]] = {
            "visual": list(record.extra["visual_geoms"]),
            "collision": list(record.extra["collision_geoms"]),
        }
    _hidden_material(builder.spec)
    park = _park_offset(builder, uid)
    body = builder.spec.body(uid)
    body.simple = False  # the inertial frame changes per env: keep a general mass matrix
    items = (
        [(f, f, None) for f in files]
        if factors is None
        else [(scale_key(f), record.extra["mesh_file"], tuple(float(v) for v in f)) for f in factors]
    )
    for key, fpath, factor in items:
        if key in variants:
            continue
        name = f"{uid}/v{len(variants)}"
        mesh, parts = load_variant_parts(cfg, fpath, factor)
        asset = add_mesh_asset(builder.spec, f"{name}/visual", mesh)
        vgeom = body.add_geom(
            name=f"{name}/visual",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=asset,
            material=HIDDEN_MATERIAL,
            rgba=[0, 0, 0, 0],
            pos=park,
        )
        vgeom.contype = vgeom.conaffinity = 0
        vgeom.group, vgeom.density = VISUAL_GROUP, 0.0
        collision = add_collision_geoms(builder.spec, body, name, parts, cfg)
        for gname in collision:
            geom = builder.spec.geom(gname)
            if park is None:
                geom.contype, geom.conaffinity = PARKED, 0
            else:  # a colliding geom, parked out of reach
                geom.pos = park
            geom.mass, geom.density = 0.0, 0.0
        variants[key] = {"visual": [vgeom.name], "collision": collision, "parts": parts, "factor": factor}
    if not record.extra.get("variant_hook"):
        record.extra["variant_hook"] = True
        builder.on_compile(lambda model: _inertials(builder, uid, model))
    return [key for key, _, _ in items]


def _park_offset(builder: Any, uid: str) -> Any:
    """Where ``uid``'s unused variants are parked (body frame), or ``None`` (collision bits)."""
    if not parks_variants(builder):
        return None
    record = builder.record(uid)
    if "park" not in record.extra:
        others = sum(1 for r in builder.records.values() if "park" in r.extra)
        record.extra["park"] = [0.0, 0.0, PARK_HEIGHT + PARK_SPACING * others]
    return record.extra["park"]


def _hidden_material(spec: mujoco.MjSpec) -> None:
    if not any(m.name == HIDDEN_MATERIAL for m in spec.materials):
        spec.add_material(name=HIDDEN_MATERIAL, rgba=[0, 0, 0, 0])


def _inertials(builder: Any, uid: str, model: mujoco.MjModel) -> None:
    """Each variant's mass, centre of mass and inertia, as MuJoCo computes them (a scaled
    variant keeps the object's mass: its inertia scales along)."""
    from embodichain_core.sim.scene_build.builder_objects import add_collision_geoms

    record = builder.record(uid)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, uid)
    mass0 = None
    for variant in record.extra["variants"].values():
        if "parts" not in variant:
            variant["inertial"] = tuple(np.array(getattr(model, f)[base]) for f in _INERTIAL)
            mass0 = float(model.body_mass[base])
            continue
        spec = mujoco.MjSpec()
        body = spec.worldbody.add_body(name="b")
        body.add_freejoint()
        add_collision_geoms(spec, body, "b", variant["parts"], record.cfg)
        small = spec.compile()
        mass, ipos, iquat, inertia = (np.array(getattr(small, f)[1]) for f in _INERTIAL)
        if variant.get("factor") is not None and mass0 is not None:
            inertia, mass = inertia * (mass0 / mass), np.array(mass0)
        variant["inertial"] = (mass, ipos, iquat, inertia)


_INERTIAL = ("body_mass", "body_ipos", "body_iquat", "body_inertia")


def _park(scene: Any, park: Sequence[float], geoms: list[tuple[int, int]], on: np.ndarray, env_ids: Any) -> None:
    """Move the enabled variants' geoms home and park the others (variants after the first
    were compiled parked)."""
    offset = np.asarray(park, dtype=np.float64)
    index = [g for _, g in geoms]
    parked_at_compile = np.array([v > 0 for v, _ in geoms], dtype=np.float64)[:, None] * offset
    home = scene.model.geom_pos[index] - parked_at_compile
    scene.sim.set_model_field("geom_pos", env_ids, index, np.where(on[..., None], home, home + offset))


def apply_variants(scene: Any, uid: str, keys: Sequence[str], env_ids: Any) -> None:
    """Enable variant ``keys[i]`` (geoms and inertia) in env ``env_ids[i]``; disable the others."""
    record = scene.builder.record(uid)
    variants = record.extra.get("variants", {})
    names = list(variants)
    for key in set(keys):
        if key not in variants:
            raise ValueError(
                f"{uid}: {key!r} was not reserved; call scene.reserve_mesh_variants({uid!r}, files) "
                f"or reserve_scale_variants before build (reserved: {names})"
            )
    model, sim = scene.model, scene.sim
    choice = np.array([names.index(k) for k in keys], dtype=np.int64)

    def find(kind: Any, name: str) -> int:
        return mujoco.mj_name2id(model, kind, name)

    mat = find(mujoco.mjtObj.mjOBJ_MATERIAL, record.extra["material"])
    hidden = find(mujoco.mjtObj.mjOBJ_MATERIAL, HIDDEN_MATERIAL)
    collision = () if "park" in record.extra else (("geom_contype", 1, PARKED), ("geom_conaffinity", ALL_BITS, 0))
    for part, fields in (("collision", collision), ("visual", (("geom_matid", mat, hidden),))):
        geoms = [(v, find(mujoco.mjtObj.mjOBJ_GEOM, g)) for v, name in enumerate(names) for g in variants[name][part]]
        on = choice[:, None] == np.array([v for v, _ in geoms])[None, :]
        index = [g for _, g in geoms]
        for field, yes, no in fields:
            sim.set_model_field(field, env_ids, index, np.where(on, yes, no))
        if part == "visual":  # MuJoCo's default geom rgba lets the material's colour show
            sim.set_model_field("geom_rgba", env_ids, index, np.where(on[..., None], [0.5, 0.5, 0.5, 1.0], 0.0))
        if "park" in record.extra:
            _park(scene, record.extra["park"], geoms, on, env_ids)
    body = find(mujoco.mjtObj.mjOBJ_BODY, uid)
    for k, field in enumerate(_INERTIAL):
        stacked = np.stack([np.asarray(variants[name]["inertial"][k]) for name in names])
        sim.set_model_field(field, env_ids, body, stacked[choice])
