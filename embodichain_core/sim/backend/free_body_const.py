"""``mj_setConst`` in closed form for the inertial properties of free-floating bodies.

Randomizing a dynamic object's mass or centre of mass on every reset must update
the constants MuJoCo derives from them (``body_invweight0``, ``dof_M0``,
``body_subtreemass``, bounding volumes...). ``mj_setConst`` recomputes them for the
*whole* model, robot included. For a body
that hangs directly off the world on a free joint, with nothing attached to it,
they follow from that body's own inertia in closed form, which this module
evaluates for every env at once in numpy (:class:`FreeBodyConstants`). At the
reference configuration, with ``m`` the mass, ``I`` the principal inertia, ``R``
the inertial frame's rotation and ``c`` the centre of mass in the body frame:

* the joint-space inertia has ``m`` on the translational diagonal and
  ``R diag(I) R^T + m ([c]x)^T [c]x`` as the rotational block, so ``dof_M0`` is
  ``m`` and ``sum_k R_jk^2 I_k + m (|c|^2 - c_j^2)``;
* its inverse, seen from the centre of mass, is ``diag(1/m, I^-1)``:
  ``body_invweight0 = (1/m, mean(1/I))``; the free joint's translational
  ``dof_invweight0`` adds ``(|c|^2 sum(1/I) - sum(c'^2 / I)) / 3`` (``c'``: ``c`` in the
  inertial frame), the rotational one is ``mean(1/I)``;
* ``dof_length`` of the rotations is the body size MuJoCo's statistics use (the
  largest of ``|c|`` and ``rbound + |c - geom_pos|``, at least 1e-5);
* the bounding-volume leaves are the geoms' boxes in the inertial frame, inner
  nodes the union of their children; ``*_sameframe`` follow MuJoCo's rules.

The world's subtree mass is re-summed. Eligible bodies: children of the world with
exactly one free joint, no armature on it, no child bodies, no actuator, tendon or
flex attached, and no camera or light tracking a centre of mass (whose
``*_poscom0`` reference would change). Anything else takes the full
``Batch.set_const``; ``tests/test_free_body_const.py`` checks that both give the
same derived fields.
"""

from __future__ import annotations

from typing import Callable, Iterable, Optional

import mujoco
import mujoco.batch as mjbatch
import numpy as np

from embodichain_core.sim.backend.free_body_geometry import (
    GEOMETRY_FIELDS,
    GeomLayout,
    body_sameframe,
    member_sameframe,
    null_quat,
    null_vec,
    quat_to_mat,
)

INERTIAL_FIELDS = frozenset({"body_mass", "body_inertia", "body_ipos", "body_iquat"})
"""Fields whose change the closed form absorbs (for eligible bodies)."""
FILTER_FIELDS = frozenset({"geom_contype", "geom_conaffinity"})
"""Collision filters: every body's aggregate (the OR of its geoms') is recomputed directly."""

_COM_TRACKING = (int(mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM),)


def eligible_bodies(model: mujoco.MjModel) -> list[int]:
    """Ids of the bodies whose inertial constants the closed form covers."""
    if any(int(m) in _COM_TRACKING for m in list(model.cam_mode) + list(model.light_mode)):
        return []
    attached = _attached_bodies(model)
    out = []
    for b in range(1, model.nbody):
        if model.body_parentid[b] != 0 or model.body_jntnum[b] != 1 or b in attached:
            continue
        if model.jnt_type[model.body_jntadr[b]] != mujoco.mjtJoint.mjJNT_FREE:
            continue
        if (model.body_parentid[1:] == b).any():
            continue
        if np.any(model.dof_armature[model.body_dofadr[b] : model.body_dofadr[b] + 6] != 0):
            continue
        out.append(b)
    return out


def _attached_bodies(model: mujoco.MjModel) -> set[int]:
    """Bodies reached by an actuator, a tendon or a flex (their constants involve more)."""
    out: set[int] = set()
    for i in range(model.nu):
        trn, tid = int(model.actuator_trntype[i]), int(model.actuator_trnid[i, 0])
        if trn in (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT)):
            out.add(int(model.jnt_bodyid[tid]))
        elif trn in (int(mujoco.mjtTrn.mjTRN_SITE), int(mujoco.mjtTrn.mjTRN_SLIDERCRANK)):
            out.add(int(model.site_bodyid[tid]))
        elif trn == int(mujoco.mjtTrn.mjTRN_BODY):
            out.add(tid)
    for w in range(model.nwrap):
        kind, obj = int(model.wrap_type[w]), int(model.wrap_objid[w])
        if kind == int(mujoco.mjtWrap.mjWRAP_SITE):
            out.add(int(model.site_bodyid[obj]))
        elif kind in (int(mujoco.mjtWrap.mjWRAP_SPHERE), int(mujoco.mjtWrap.mjWRAP_CYLINDER)):
            out.add(int(model.geom_bodyid[obj]))
        elif kind == int(mujoco.mjtWrap.mjWRAP_JOINT):
            out.add(int(model.jnt_bodyid[obj]))
    out.update(int(b) for b in np.asarray(model.flex_vertbodyid).reshape(-1))
    return out


_Get = Callable[[str, np.ndarray], np.ndarray]  # _EnvRows.get
_Put = Callable[[str, np.ndarray, np.ndarray], None]  # _EnvRows.put


class FreeBodyConstants:
    """Refreshes the derived constants of the eligible bodies of ``model`` in ``batch``'s
    per-env (expanded) fields, for some envs, without ``mj_setConst``.

    Args:
        model: the scene model.
        batch: the scene's batch (its expanded fields are read and written).
        bodies: the eligible body ids (see :func:`eligible_bodies`).
    """

    def __init__(self, model: mujoco.MjModel, batch: mjbatch.Batch, bodies: list[int]):
        self.model, self.batch = model, batch
        self.bodies = np.asarray(sorted(bodies), dtype=np.int64)
        self.dofs = (model.body_dofadr[self.bodies][:, None] + np.arange(6)).astype(np.int64)  # (nb, 6)
        self.rot_dofs = self.dofs[:, 3:]
        self.world_children = np.flatnonzero(model.body_parentid == 0)[1:]
        self.layout = GeomLayout(model, self.bodies)
        self.filter_bodies = np.flatnonzero(model.body_geomnum > 0)
        self.filter_starts = model.body_geomadr[self.filter_bodies].astype(np.int64)
        self.all_geoms = np.arange(model.ngeom)
        self._blocks: dict[int, tuple[np.ndarray, Optional[slice]]] = {}  # see _EnvRows

    def update(self, rows: Optional[np.ndarray] = None, fields: Optional[Iterable[str]] = None) -> bool:
        """Recompute the constants for env ``rows`` (sorted, unique int64; None: all).

        Args:
            rows: the envs.
            fields: the fields written since the last update (None: any); without
                ``body_ipos``/``body_iquat`` the frame-dependent constants are kept.

        Returns:
            ``False`` (nothing written) where the closed form does not apply to the current
            values: a per-env armature on an eligible joint or per-env geoms or sites.
        """
        rows = np.arange(self.batch.nsim) if rows is None else np.asarray(rows, dtype=np.int64)
        expanded = self.batch._expanded
        if any(name in expanded for name in GEOMETRY_FIELDS):
            return False
        env_rows = _EnvRows(self.batch, self.model, rows, self._blocks)
        get, put = env_rows.get, env_rows.put
        if "dof_armature" in expanded and np.any(get("dof_armature", self.dofs) != 0):
            return False
        if fields is None or not FILTER_FIELDS.isdisjoint(fields):
            self._filter_terms(get, put)
        if fields is not None and INERTIAL_FIELDS.isdisjoint(fields):
            return True
        mass, ipos, iquat = get("body_mass", self.bodies), get("body_ipos", self.bodies), get("body_iquat", self.bodies)
        rot = quat_to_mat(iquat)  # (n, nb, 3, 3): the inertial frame in the body frame
        cc = ipos * ipos
        c2 = cc[..., 0] + cc[..., 1] + cc[..., 2]
        self._inertia_terms(put, mass, get("body_inertia", self.bodies), ipos, rot, cc, c2)
        if fields is None or "body_ipos" in fields or "body_iquat" in fields:
            self._frame_terms(put, ipos, iquat, rot, c2)
        sub = self.batch.expand("body_subtreemass")  # the world's: MuJoCo's sum over its children
        sel = slice(None) if env_rows.all else rows
        sub[sel, 0] = self.model.body_mass[0] + sub[sel][:, self.world_children].sum(axis=1)
        return True

    def _filter_terms(self, get: _Get, put: _Put) -> None:
        """``body_contype``/``body_conaffinity``: the OR of each body's geoms'."""
        for geom_field, body_field in (("geom_contype", "body_contype"), ("geom_conaffinity", "body_conaffinity")):
            flags = get(geom_field, self.all_geoms)
            put(body_field, self.filter_bodies, np.bitwise_or.reduceat(flags, self.filter_starts, axis=-1))

    def _inertia_terms(
        self,
        put: _Put,
        mass: np.ndarray,
        inertia: np.ndarray,
        ipos: np.ndarray,
        rot: np.ndarray,
        cc: np.ndarray,
        c2: np.ndarray,
    ) -> None:
        """``body_subtreemass``, ``body_invweight0``, ``dof_M0`` and ``dof_invweight0``."""
        n = max(len(mass), len(inertia), len(ipos), len(rot))
        inv_i, inv_m = 1.0 / inertia, 1.0 / mass
        mean_inv = (inv_i[..., 0] + inv_i[..., 1] + inv_i[..., 2]) / 3
        c_in = (ipos[..., None, :] @ rot)[..., 0, :]  # centre of mass in the inertial frame
        w = c_in * c_in * inv_i
        lever = c2 * mean_inv - (w[..., 0] + w[..., 1] + w[..., 2]) / 3
        out = np.empty((n, len(self.bodies), 14))  # invweight0 (2), M0 (6), dof invweight0 (6)
        out[..., 0], out[..., 1] = inv_m, mean_inv
        out[..., 2:5] = mass[..., None]
        out[..., 5:8] = ((rot * rot) @ inertia[..., None])[..., 0] + mass[..., None] * (c2[..., None] - cc)
        out[..., 8:11] = (inv_m + lever)[..., None]
        out[..., 11:14] = mean_inv[..., None]
        put("body_subtreemass", self.bodies, mass)
        put("body_invweight0", self.bodies, out[..., :2])
        put("dof_M0", self.dofs, out[..., 2:8])
        put("dof_invweight0", self.dofs, out[..., 8:])

    def _frame_terms(self, put: _Put, ipos: np.ndarray, iquat: np.ndarray, rot: np.ndarray, c2: np.ndarray) -> None:
        """``*_sameframe``, ``dof_length`` of the rotations and ``bvh_aabb``."""
        layout = self.layout
        put("body_sameframe", self.bodies, body_sameframe(null_vec(ipos), null_quat(iquat)))
        for kind, (ids, owner, pos, quat) in layout.rotated.items():
            if len(ids):
                put(f"{kind}_sameframe", ids, member_sameframe(pos, quat, ipos[:, owner], iquat[:, owner]))
        size = layout.sizes(ipos, np.sqrt(c2))
        put("dof_length", self.rot_dofs, np.broadcast_to(size[..., None], size.shape + (3,)))
        if len(layout.bvh.nodes):
            put("bvh_aabb", layout.bvh.nodes, layout.bvh.boxes(rot, ipos))


class _EnvRows:
    """Model fields of env ``rows`` in ``batch``: :meth:`get` reads current values
    (``(n, ...)`` where the field is per env, ``(1, ...)`` to broadcast where every env
    shares the model's); :meth:`put` writes derived values into the per-env (expanded)
    field, as one slice when every env is written and the elements are a contiguous run
    (``blocks`` caches which element-id arrays are)."""

    def __init__(
        self,
        batch: mjbatch.Batch,
        model: mujoco.MjModel,
        rows: np.ndarray,
        blocks: dict[int, tuple[np.ndarray, Optional[slice]]],
    ):
        self.batch, self.model, self.rows, self.blocks = batch, model, rows, blocks
        self.all = len(rows) == batch.nsim

    def _select(self, index: np.ndarray) -> tuple:
        """``field[selector]`` of elements ``index`` (any shape) of the rows: ``(n,) + index.shape``."""
        return self.rows.reshape((-1,) + (1,) * index.ndim), index

    def get(self, name: str, index: np.ndarray) -> np.ndarray:
        per_env = self.batch._expanded.get(name)
        if per_env is None:
            return getattr(self.model, name)[index][None]
        return per_env[:, index] if self.all else per_env[self._select(index)]

    def put(self, name: str, index: np.ndarray, values: np.ndarray) -> None:
        field = self.batch.expand(name)
        if not self.all:
            field[self._select(index)] = values
            return
        block = _block(index, self.blocks)
        if block is None:
            field[:, index] = values
        else:
            field[:, block] = values.reshape(values.shape[:1] + (-1,) + field.shape[2:])


def _block(index: np.ndarray, cache: dict[int, tuple[np.ndarray, Optional[slice]]]) -> Optional[slice]:
    """``index`` (element ids, any shape) as a slice when it is a contiguous run."""
    hit = cache.get(id(index))
    if hit is None or hit[0] is not index:
        flat = index.reshape(-1)
        run = len(flat) > 0 and bool((np.diff(flat) == 1).all())
        hit = (index, slice(int(flat[0]), int(flat[-1]) + 1) if run else None)
        cache[id(index)] = hit
    return hit[1]
