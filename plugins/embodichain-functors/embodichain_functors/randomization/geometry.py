"""Geometry randomization: per-env scale of primitive rigid objects.

Each env gets its own size through the per-env model fields ``geom_size``,
``geom_rbound`` and ``geom_aabb`` (collision and rendering follow); the mass is
kept and the inertia follows the new extents. MuJoCo meshes are shared by every
env, so mesh objects cannot be rescaled per env (use ``replace_assets_from_group``
with meshes of several sizes instead).
"""

from __future__ import annotations

import weakref
from typing import Any, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.rigid_object import RigidObject

from embodichain_functors._common import ParamError, as_range, entity_of, env_ids_of, uniform, validated
from embodichain_functors._sim import read_model, write_model

__all__ = ["randomize_rigid_object_scale", "randomize_rigid_objects_scale", "body_scale_factor"]

_G = mujoco.mjtGeom
_SCALABLE = (int(_G.mjGEOM_BOX), int(_G.mjGEOM_SPHERE), int(_G.mjGEOM_CYLINDER), int(_G.mjGEOM_CAPSULE))
_FACTORS: "weakref.WeakKeyDictionary[RigidObject, torch.Tensor]" = weakref.WeakKeyDictionary()


def body_scale_factor(obj: RigidObject) -> torch.Tensor:
    """(N, 3) per-env scale factors applied to ``obj`` (ones until randomized)."""
    if obj not in _FACTORS:
        _FACTORS[obj] = torch.ones(obj.num_envs, 3, dtype=torch.float64)
    return _FACTORS[obj]


def _sizes(gtype: int, size: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scaled ``geom_size``, ``geom_rbound`` and aabb half-extents of (n,) geoms of one type."""
    n = f.shape[0]
    if gtype == _G.mjGEOM_BOX:
        s = size[None, :] * f
        return s, np.linalg.norm(s, axis=1), s
    if gtype == _G.mjGEOM_SPHERE:
        r = size[0] * f.max(axis=1)
        return np.stack((r, np.zeros(n), np.zeros(n)), 1), r, np.stack((r, r, r), 1)
    r, h = size[0] * f[:, :2].max(axis=1), size[1] * f[:, 2]
    out = np.stack((r, h, np.zeros(n)), 1)
    if gtype == _G.mjGEOM_CAPSULE:
        return out, r + h, np.stack((r, r, r + h), 1)
    return out, np.hypot(r, h), np.stack((r, r, h), 1)


def _inertia_factor(half: np.ndarray) -> np.ndarray:
    """Box-like inertia factors ``(e_y^2 + e_z^2, ...)`` of (n, 3) half-extents."""
    sq = half ** 2
    return np.stack((sq[:, 1] + sq[:, 2], sq[:, 0] + sq[:, 2], sq[:, 0] + sq[:, 1]), 1)


def _check_scale(env: Any, entity_cfg: SceneEntityCfg, scale_factor_range: Any, same_scale_all_axes: bool = True,
                 functor: str = "randomize_rigid_object_scale", param: str = "entity_cfg") -> None:
    obj = entity_of(env, entity_cfg, functor, (RigidObject,), param)
    types = [int(env.scene.model.geom_type[g]) for g in obj.geom_ids]
    if not types or any(t not in _SCALABLE for t in types):
        raise ParamError(functor, param, f"{entity_cfg.uid!r} is not a primitive shape (meshes are shared by every "
                                         "env; scale meshes with replace_assets_from_group)")
    low, _ = as_range(scale_factor_range, functor, "scale_factor_range", 3)
    if (low <= 0).any():
        raise ParamError(functor, "scale_factor_range", f"scale factors must be > 0, got {scale_factor_range!r}")


def draw_scale(env: Any, scale_factor_range: Any, n: int, same_scale_all_axes: bool, functor: str) -> torch.Tensor:
    """(n, 3) scale factors (one factor for all axes, from the x bounds, when ``same_scale_all_axes``)."""
    low, high = as_range(scale_factor_range, functor, "scale_factor_range", 3)
    if same_scale_all_axes:
        return uniform(env, low[0], high[0], n).reshape(n, 1).expand(n, 3)
    return uniform(env, low, high, n)


def apply_scale(env: Any, obj: RigidObject, ids: torch.Tensor, factor: torch.Tensor) -> None:
    """Scale ``obj``'s geoms in ``ids`` to ``factor`` (n, 3) times the configured size."""
    model, f = env.scene.model, factor.numpy()
    old = body_scale_factor(obj)[ids].numpy()
    writes, half_new, half_old = [], None, None
    for g in obj.geom_ids:
        gtype, size = int(model.geom_type[g]), np.array(model.geom_size[g])
        new_size, rbound, half = _sizes(gtype, size, f)
        writes += [("geom_size", g, new_size), ("geom_rbound", g, rbound), ("geom_aabb", (g, slice(3, 6)), half)]
        if half_new is None:
            half_new, half_old = half, _sizes(gtype, size, old)[2]
    inertia = read_model(env.sim, "body_inertia", ids, obj.body_id)
    inertia = inertia * _inertia_factor(half_new) / np.maximum(_inertia_factor(half_old), 1e-18)
    write_model(env.sim, ids, writes + [("body_inertia", obj.body_id, inertia)])
    body_scale_factor(obj)[ids] = factor


@validated(_check_scale)
def randomize_rigid_object_scale(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, scale_factor_range: Any,
                                 same_scale_all_axes: bool = True) -> None:
    """Scale a primitive rigid object by a per-env factor of its configured size.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the rigid object (box, sphere, cylinder or capsule).
        scale_factor_range: ``[low, high]``, ``[[s], [s]]`` or per axis ``[[sx, sy, sz], [...]]``.
        same_scale_all_axes: one factor (from the x bounds) for every axis.

    Example:
        ``{"func": "randomize_rigid_object_scale", "mode": "reset", "params": {"entity_cfg": {"uid": "cube"},
        "scale_factor_range": [[0.8], [1.2]]}}``
    """
    ids = env_ids_of(env, env_ids)
    factor = draw_scale(env, scale_factor_range, len(ids), same_scale_all_axes, "randomize_rigid_object_scale")
    apply_scale(env, env.scene[entity_cfg.uid], ids, factor)


def _check_scales(env: Any, entity_cfgs: Sequence[SceneEntityCfg], scale_factor_range: Any,
                  same_scale_all_axes: bool = True, shared_sample: bool = False) -> None:
    if not isinstance(entity_cfgs, (list, tuple)) or not entity_cfgs:
        raise ParamError("randomize_rigid_objects_scale", "entity_cfgs", "must be a non-empty list of entities")
    for cfg in entity_cfgs:
        _check_scale(env, cfg, scale_factor_range, functor="randomize_rigid_objects_scale", param="entity_cfgs")


@validated(_check_scales)
def randomize_rigid_objects_scale(env: Any, env_ids: Any, entity_cfgs: Sequence[SceneEntityCfg],
                                  scale_factor_range: Any, same_scale_all_axes: bool = True,
                                  shared_sample: bool = False) -> None:
    """Scale several primitive rigid objects per env, each its own factor or one shared factor.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfgs: the rigid objects.
        scale_factor_range: ``[low, high]`` or per axis ``[[sx, sy, sz], [...]]``.
        same_scale_all_axes: one factor for every axis.
        shared_sample: every object of an env gets the same factor.

    Example:
        ``{"func": "randomize_rigid_objects_scale", "mode": "reset", "params": {"entity_cfgs":
        [{"uid": "cube"}, {"uid": "ball"}], "scale_factor_range": [0.9, 1.1], "shared_sample": true}}``
    """
    ids = env_ids_of(env, env_ids)
    shared = draw_scale(env, scale_factor_range, len(ids), same_scale_all_axes, "randomize_rigid_objects_scale") \
        if shared_sample else None
    for cfg in entity_cfgs:
        factor = shared if shared is not None else draw_scale(env, scale_factor_range, len(ids), same_scale_all_axes,
                                                              "randomize_rigid_objects_scale")
        apply_scale(env, env.scene[cfg["uid"] if isinstance(cfg, dict) else cfg.uid], ids, factor)
