"""Geometry randomization: per-env scale of rigid objects.

A primitive (box, sphere, cylinder, capsule) gets any size per env through the
per-env model fields ``geom_size``, ``geom_rbound`` and ``geom_aabb`` (collision
and rendering follow). A mesh is shared by every env, so a mesh object takes one
of a few scaled copies compiled into the model before build (``modify_scene``;
``mesh_scale_levels`` of them, see :func:`mesh_levels`): the drawn factor is
rounded to the nearest one. Either way the mass is kept and the inertia follows
the new shape.
"""

from __future__ import annotations

import weakref
from typing import Any, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.scene_build.variants import scale_key

from embodichain_functors._common import ParamError, as_range, check_positive, entity_of, env_ids_of, uniform
from embodichain_functors._functor import CheckedFunctor
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
    sq = half**2
    return np.stack((sq[:, 1] + sq[:, 2], sq[:, 0] + sq[:, 2], sq[:, 0] + sq[:, 1]), 1)


def _is_mesh(scene: Any, uid: str) -> bool:
    record = scene.builder.records.get(uid) if scene.builder is not None else None
    return record is not None and "mesh_file" in record.extra


def _check_scale(
    env: Any, entity_cfg: SceneEntityCfg, scale_factor_range: Any, functor: str, param: str = "entity_cfg"
) -> None:
    obj = entity_of(env, entity_cfg, functor, (RigidObject,), param)
    low, _ = as_range(scale_factor_range, functor, "scale_factor_range", 3)
    if (low <= 0).any():
        raise ParamError(functor, "scale_factor_range", f"scale factors must be > 0, got {scale_factor_range!r}")
    if _is_mesh(env.scene, obj.uid):
        variants = env.scene.builder.records[obj.uid].extra.get("variants", {})
        files = [k for k, v in variants.items() if v.get("factor") is None and "parts" in v]
        if files:
            raise ParamError(
                functor,
                param,
                f"{obj.uid!r} also swaps meshes (replace_assets_from_group); scale the meshes of its folder instead",
            )
        return
    types = [int(env.scene.model.geom_type[g]) for g in obj.geom_ids]
    if not types or any(t not in _SCALABLE for t in types):
        raise ParamError(
            functor,
            param,
            f"{entity_cfg.uid!r} has geoms that cannot be scaled per env "
            "(boxes, spheres, cylinders, capsules and meshes can)",
        )


def mesh_levels(scale_factor_range: Any, same_scale_all_axes: bool, levels: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """The precompiled scales of a mesh object: ``(factors (k, 3), per-axis values)``.

    With one factor for all axes, ``levels`` values at the centres of equal bins of the
    x range; per axis, a grid of ``round(levels ** (1/3))`` bin centres on each axis.
    Drawn factors round to the nearest value on each axis, so every bin is equally likely.
    """
    low, high = (t.numpy() for t in as_range(scale_factor_range, "mesh_levels", "scale_factor_range", 3))
    if same_scale_all_axes:
        values = _centres(low[0], high[0], levels)
        return np.repeat(values[:, None], 3, axis=1), [values] * 3
    per_axis = max(1, int(round(levels ** (1.0 / 3.0))))
    axes = [_centres(low[a], high[a], per_axis) for a in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return grid, axes


def _centres(low: float, high: float, n: int) -> np.ndarray:
    n = 1 if high <= low else n
    return low + (np.arange(n) + 0.5) * (high - low) / n


def draw_scale(
    env: Any, scale_factor_range: Any, ids: torch.Tensor, same_scale_all_axes: bool, functor: str
) -> torch.Tensor:
    """(n, 3) scale factors of envs ``ids`` (one factor for all axes, from the x bounds, when
    ``same_scale_all_axes``)."""
    n = len(ids)
    low, high = as_range(scale_factor_range, functor, "scale_factor_range", 3)
    if same_scale_all_axes:
        return uniform(env, ids, low[0], high[0]).reshape(n, 1).expand(n, 3)
    return uniform(env, ids, low, high)


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
    if half_new is None or half_old is None:
        raise ValueError(f"{obj.uid}: no geom to scale")
    inertia = read_model(env.sim, "body_inertia", ids, obj.body_id)
    inertia = inertia * _inertia_factor(half_new) / np.maximum(_inertia_factor(half_old), 1e-18)
    write_model(env.sim, ids, writes + [("body_inertia", obj.body_id, inertia)])
    body_scale_factor(obj)[ids] = factor


class _ScaleFunctor(CheckedFunctor):
    """Shared machinery: scaled mesh variants before build, primitive or mesh scaling after."""

    @staticmethod
    def _uids(params: dict) -> list[str]:
        raise NotImplementedError

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Compile the scaled copies of mesh objects (bad params are reported by ``check``)."""
        params = cfg.params
        try:
            factors, _ = mesh_levels(
                params.get("scale_factor_range"),
                bool(params.get("same_scale_all_axes", True)),
                int(params.get("mesh_scale_levels", 8)),
            )
            uids = cls._uids(params)
        except (ParamError, TypeError, ValueError, KeyError):
            return
        for uid in uids:
            if _is_mesh(scene, uid) and (factors > 0).all():
                scene.reserve_scale_variants(uid, [tuple(f) for f in factors])

    def _check_levels(self, mesh_scale_levels: Any) -> None:
        name = type(self).__name__
        check_positive(mesh_scale_levels, name, "mesh_scale_levels")
        if int(mesh_scale_levels) != mesh_scale_levels:
            raise ParamError(name, "mesh_scale_levels", f"must be a whole number, got {mesh_scale_levels!r}")

    def _apply(self, env: Any, uid: str, ids: torch.Tensor, factor: torch.Tensor, params: dict) -> None:
        obj = env.scene[uid]
        if not _is_mesh(env.scene, uid):
            apply_scale(env, obj, ids, factor)
            return
        _, axes = mesh_levels(params["scale_factor_range"], params["same_scale_all_axes"], params["mesh_scale_levels"])
        f = factor.numpy()
        snapped = np.stack([axis[np.abs(f[:, a : a + 1] - axis[None, :]).argmin(1)] for a, axis in enumerate(axes)], 1)
        env.scene.set_mesh_variants(uid, [scale_key(tuple(v)) for v in snapped], ids)
        body_scale_factor(obj)[ids] = torch.from_numpy(snapped)


class randomize_rigid_object_scale(_ScaleFunctor):
    """Scale a rigid object by a per-env factor of its configured size.

    Primitives (box, sphere, cylinder, capsule) take any factor; a mesh object takes the
    nearest of ``mesh_scale_levels`` scaled copies compiled before build. The mass is
    kept; the inertia follows the shape.

    Args (params):
        entity_cfg: the rigid object.
        scale_factor_range: ``[low, high]``, ``[[s], [s]]`` or per axis ``[[sx, sy, sz], [...]]``.
        same_scale_all_axes: one factor (from the x bounds) for every axis.
        mesh_scale_levels: scaled copies of a mesh (per axis: a grid of ``round(levels ** (1/3))``
            values on each axis).

    Example:
        ``{"func": "randomize_rigid_object_scale", "mode": "reset", "params": {"entity_cfg": {"uid": "cube"},
        "scale_factor_range": [[0.8], [1.2]]}}``
    """

    @staticmethod
    def _uids(params: dict) -> list[str]:
        entity = params["entity_cfg"]
        return [entity["uid"] if isinstance(entity, dict) else entity.uid]

    def check(
        self,
        env: Any,
        entity_cfg: Any = None,
        scale_factor_range: Any = None,
        same_scale_all_axes: bool = True,
        mesh_scale_levels: Any = 8,
    ) -> None:
        self._check_levels(mesh_scale_levels)
        _check_scale(env, entity_cfg, scale_factor_range, type(self).__name__)

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        entity_cfg: SceneEntityCfg,
        scale_factor_range: Any,
        same_scale_all_axes: bool = True,
        mesh_scale_levels: int = 8,
    ) -> None:
        ids = env_ids_of(env, env_ids)
        factor = draw_scale(env, scale_factor_range, ids, same_scale_all_axes, type(self).__name__)
        self._apply(
            env,
            entity_cfg.uid,
            ids,
            factor,
            {
                "scale_factor_range": scale_factor_range,
                "same_scale_all_axes": same_scale_all_axes,
                "mesh_scale_levels": mesh_scale_levels,
            },
        )


class randomize_rigid_objects_scale(_ScaleFunctor):
    """Scale several rigid objects per env, each its own factor or one shared factor.

    Primitives take any factor; mesh objects the nearest of their precompiled scales
    (see ``randomize_rigid_object_scale``).

    Args (params):
        entity_cfgs: the rigid objects.
        scale_factor_range: ``[low, high]`` or per axis ``[[sx, sy, sz], [...]]``.
        same_scale_all_axes: one factor for every axis.
        shared_sample: every object of an env gets the same factor.
        mesh_scale_levels: scaled copies of each mesh object.

    Example:
        ``{"func": "randomize_rigid_objects_scale", "mode": "reset", "params": {"entity_cfgs":
        [{"uid": "cube"}, {"uid": "ball"}], "scale_factor_range": [0.9, 1.1], "shared_sample": true}}``
    """

    @staticmethod
    def _uids(params: dict) -> list[str]:
        return [c["uid"] if isinstance(c, dict) else c.uid for c in params["entity_cfgs"]]

    def check(
        self,
        env: Any,
        entity_cfgs: Any = None,
        scale_factor_range: Any = None,
        same_scale_all_axes: bool = True,
        shared_sample: bool = False,
        mesh_scale_levels: Any = 8,
    ) -> None:
        name = type(self).__name__
        if not isinstance(entity_cfgs, (list, tuple)) or not entity_cfgs:
            raise ParamError(name, "entity_cfgs", "must be a non-empty list of entities")
        self._check_levels(mesh_scale_levels)
        for cfg in entity_cfgs:
            _check_scale(env, cfg, scale_factor_range, name, param="entity_cfgs")

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        entity_cfgs: Sequence[SceneEntityCfg],
        scale_factor_range: Any,
        same_scale_all_axes: bool = True,
        shared_sample: bool = False,
        mesh_scale_levels: int = 8,
    ) -> None:
        ids = env_ids_of(env, env_ids)
        name = type(self).__name__
        params = {
            "scale_factor_range": scale_factor_range,
            "same_scale_all_axes": same_scale_all_axes,
            "mesh_scale_levels": mesh_scale_levels,
        }
        shared = draw_scale(env, scale_factor_range, ids, same_scale_all_axes, name) if shared_sample else None
        for cfg in entity_cfgs:
            factor = (
                shared if shared is not None else draw_scale(env, scale_factor_range, ids, same_scale_all_axes, name)
            )
            self._apply(env, cfg["uid"] if isinstance(cfg, dict) else cfg.uid, ids, factor, params)
