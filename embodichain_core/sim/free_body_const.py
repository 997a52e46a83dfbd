"""Cheap ``mj_setConst`` for the inertial properties of free-floating bodies.

Randomizing a dynamic object's mass or centre of mass on every reset must update
the constants MuJoCo derives from them (``body_invweight0``, ``dof_M0``,
``body_subtreemass``, bounding volumes...). ``mj_setConst`` recomputes them for the
*whole* model, robot included (12 us per env for a 7-DoF arm scene). For a body
that hangs directly off the world on a free joint, with nothing attached to it,
those constants depend on that body alone, so MuJoCo can compute them on a small
*proxy* model holding only such bodies (a copy of the scene spec, everything else
deleted): same geoms, joints and compiler settings, hence the same numbers, at a
fraction of the cost. The world's subtree mass is then updated by the difference.

Eligible bodies: children of the world with exactly one free joint, no child
bodies, no actuator, tendon or flex attached, and no camera or light tracking a
centre of mass (whose ``*_poscom0`` reference would change). Anything else takes
the full ``Batch.set_const``. ``tests/test_free_body_const.py`` checks that both
give the same derived fields.
"""

from __future__ import annotations

from typing import Any, Iterable, Optional

import mujoco
import mujoco.batch as mjbatch
import numpy as np

INERTIAL_FIELDS = frozenset({"body_mass", "body_inertia", "body_ipos", "body_iquat"})
"""Fields whose change the proxy can absorb (for eligible bodies)."""

_DERIVED = ("body_invweight0", "body_subtreemass", "body_sameframe", "dof_M0", "dof_invweight0", "dof_length")
_COM_TRACKING = (int(mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM),)


def eligible_bodies(model: mujoco.MjModel) -> list[int]:
    """Ids of the bodies whose inertial constants the proxy can recompute."""
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


class FreeBodyConstants:
    """A proxy batch of the eligible bodies of ``model``; :meth:`update` refreshes the
    main batch's derived constants of those bodies for some envs.

    Args:
        spec: the spec ``model`` was compiled from (copied, not changed).
        model: the scene model.
        batch: the scene's batch.
        bodies: the eligible body ids (see :func:`eligible_bodies`).
    """

    def __init__(self, spec: mujoco.MjSpec, model: mujoco.MjModel, batch: mjbatch.Batch, bodies: list[int]):
        self.model, self.batch = model, batch
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in bodies]
        self.proxy = _proxy_model(spec, set(names))
        self.proxy_batch = mjbatch.Batch(self.proxy, batch.nsim, nthread=batch.nthread)
        pids = [mujoco.mj_name2id(self.proxy, mujoco.mjtObj.mjOBJ_BODY, n) for n in names]
        self._maps = _index_maps(model, self.proxy, list(bodies), pids)

    def update(self, ids: Optional[np.ndarray]) -> None:
        """Recompute the eligible bodies' derived constants for envs ``ids`` (None: all)."""
        rows = np.arange(self.batch.nsim) if ids is None else np.asarray(ids)
        self._copy_inputs(rows)
        self.proxy_batch.set_const(None if ids is None else rows.astype(np.int32))
        self._copy_outputs(rows)

    def _copy_inputs(self, rows: np.ndarray) -> None:
        """Every per-env setConst input of the mapped elements, main -> proxy."""
        expanded = self.batch._expanded  # the fields with per-env values (few)
        for name in _INPUTS_SET.intersection(expanded):
            src, dst = self._maps[_kind(name)]
            self.proxy_batch.expand(name)[rows[:, None], dst[None, :]] = expanded[name][rows[:, None], src[None, :]]

    def _copy_outputs(self, rows: np.ndarray) -> None:
        """The proxy's derived constants of the mapped elements, proxy -> main."""
        main, proxy, col = self.batch.expand, self.proxy_batch.expand, rows[:, None]
        sub = main("body_subtreemass")
        src_b = self._maps["body"][0]
        before = sub[col, src_b].sum(axis=1)
        for name, kind in _OUTPUTS:
            src, dst = self._maps[kind]
            main(name)[col, src] = proxy(name)[col, dst]
        sub[rows, 0] += sub[col, src_b].sum(axis=1) - before


def _kind(name: str) -> str:
    if name in ("qpos0", "qpos_spring"):
        return "qpos"
    return {"jnt": "jnt", "dof": "dof", "body": "body", "geom": "geom"}.get(name.split("_", 1)[0], "other")


_INPUTS = tuple(sorted(n for n in mujoco.MjModel._setconst_inputs
                      if n in mjbatch.MODEL_FIELDS and _kind(n) in ("qpos", "body", "jnt", "dof", "geom")))
"""The per-env setConst inputs that may concern a proxy body (copied to the proxy)."""
_INPUTS_SET = frozenset(_INPUTS)
_OUTPUTS = tuple((name, _kind(name)) for name in _DERIVED) + (("bvh_aabb", "bvh"),)


def _proxy_model(spec: mujoco.MjSpec, keep: set[str]) -> mujoco.MjModel:
    """A copy of ``spec`` with only the world bodies named in ``keep`` (and their meshes)."""
    proxy = spec.copy()
    world = proxy.worldbody
    for body in list(world.bodies):
        if body.name not in keep:
            proxy.delete(body)
    for group in (world.geoms, world.sites, world.cameras, world.lights, proxy.actuators, proxy.sensors,
                  proxy.tendons, proxy.equalities, proxy.excludes, proxy.pairs, proxy.keys):
        for element in list(group):
            proxy.delete(element)
    used = {g.meshname for b in world.bodies for g in b.geoms if g.meshname}
    for mesh in list(proxy.meshes):
        if mesh.name not in used:
            proxy.delete(mesh)
    return proxy.compile()


def _index_maps(model: mujoco.MjModel, proxy: mujoco.MjModel, bodies: list[int],
                pids: list[int]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{kind: (main indices, proxy indices)}`` of bodies, joints, dofs, geoms, bvh nodes."""
    pairs: dict[str, list[tuple[int, int]]] = {k: [] for k in ("body", "jnt", "dof", "geom", "bvh", "qpos")}
    for b, p in zip(bodies, pids):
        pairs["body"].append((b, p))
        pairs["jnt"].append((int(model.body_jntadr[b]), int(proxy.body_jntadr[p])))
        jnt, pjnt = int(model.body_jntadr[b]), int(proxy.body_jntadr[p])
        pairs["qpos"] += _ranges(model.jnt_qposadr[jnt], proxy.jnt_qposadr[pjnt], 7)
        pairs["dof"] += _ranges(model.body_dofadr[b], proxy.body_dofadr[p], model.body_dofnum[b])
        pairs["geom"] += _ranges(model.body_geomadr[b], proxy.body_geomadr[p], model.body_geomnum[b])
        pairs["bvh"] += _ranges(model.body_bvhadr[b], proxy.body_bvhadr[p], model.body_bvhnum[b])
    return {k: (np.array([a for a, _ in v], dtype=np.int64), np.array([c for _, c in v], dtype=np.int64))
            for k, v in pairs.items()}


def _ranges(a: Any, b: Any, n: Any) -> Iterable[tuple[int, int]]:
    return [(int(a) + k, int(b) + k) for k in range(int(n))]
