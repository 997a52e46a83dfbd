"""Geometry of the free bodies of :mod:`embodichain_core.sim.backend.free_body_const`, with
MuJoCo's definitions: rotations as ``mju_quat2Mat``, the ``*_sameframe`` rules
(tolerance 1e-6), body sizes (``dof_length``) and the bounding-volume hierarchy
(boxes in each body's inertial frame). Everything that depends only on the geoms
and sites is computed once per layout (:class:`GeomLayout`); what depends on the
bodies' inertial frames is evaluated for every env at once."""

from __future__ import annotations

import mujoco
import numpy as np

SAME_FRAME_EPS = 1e-6
"""MuJoCo's tolerance for "same frame" (the compiler's and ``mj_setConst``'s)."""
_NONE, _BODY = int(mujoco.mjtSameFrame.mjSAMEFRAME_NONE), int(mujoco.mjtSameFrame.mjSAMEFRAME_BODY)
_INERTIA, _BODYROT = int(mujoco.mjtSameFrame.mjSAMEFRAME_INERTIA), int(mujoco.mjtSameFrame.mjSAMEFRAME_BODYROT)
_INERTIAROT = int(mujoco.mjtSameFrame.mjSAMEFRAME_INERTIAROT)
_MIN_SIZE = 1e-5  # MuJoCo's smallest body size

# rotation matrix entries as a linear map of the quaternion's outer product q q^T
_QUAT_TO_MAT = np.zeros((16, 9))
for _entry, _terms in enumerate(
    (
        ((0, 0, 1), (1, 1, 1), (2, 2, -1), (3, 3, -1)),
        ((1, 2, 2), (0, 3, -2)),
        ((1, 3, 2), (0, 2, 2)),
        ((1, 2, 2), (0, 3, 2)),
        ((0, 0, 1), (1, 1, -1), (2, 2, 1), (3, 3, -1)),
        ((2, 3, 2), (0, 1, -2)),
        ((1, 3, 2), (0, 2, -2)),
        ((2, 3, 2), (0, 1, 2)),
        ((0, 0, 1), (1, 1, -1), (2, 2, -1), (3, 3, 1)),
    )
):
    for _a, _b, _coef in _terms:
        _QUAT_TO_MAT[4 * _a + _b, _entry] = _coef


def quat_to_mat(quat: np.ndarray) -> np.ndarray:
    """``(..., 4)`` wxyz quaternions to ``(..., 3, 3)`` rotation matrices (not normalized,
    the same terms as ``mju_quat2Mat``)."""
    outer = (quat[..., :, None] * quat[..., None, :]).reshape(quat.shape[:-1] + (16,))
    return (outer @ _QUAT_TO_MAT).reshape(quat.shape[:-1] + (3, 3))


def null_quat(quat: np.ndarray) -> np.ndarray:
    """Within the tolerance of the identity, either sign (MuJoCo's ``isNullQuat``)."""
    a = np.abs(quat)
    return (a[..., 1:].max(axis=-1) < SAME_FRAME_EPS) & (np.abs(a[..., 0] - 1) < SAME_FRAME_EPS)


def same_quat(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Equal within the tolerance, either sign (double cover)."""
    return (np.abs(q1 - q2).max(axis=-1) < SAME_FRAME_EPS) | (np.abs(q1 + q2).max(axis=-1) < SAME_FRAME_EPS)


def null_vec(vec: np.ndarray) -> np.ndarray:
    return np.abs(vec).max(axis=-1) < SAME_FRAME_EPS


def body_sameframe(ipos_null: np.ndarray, iquat_null: np.ndarray) -> np.ndarray:
    """``body_sameframe`` from whether the inertial frame's offset/rotation are null."""
    return np.where(iquat_null, np.where(ipos_null, _BODY, _BODYROT), _NONE)


def member_sameframe(pos: np.ndarray, quat: np.ndarray, ipos: np.ndarray, iquat: np.ndarray) -> np.ndarray:
    """``geom_sameframe``/``site_sameframe`` of elements with a rotated frame ``pos``/``quat``
    on bodies with inertial frames ``ipos``/``iquat`` (an unrotated element's class does
    not depend on the inertial frame: see :class:`GeomLayout`)."""
    rot = same_quat(quat, iquat)
    return np.where(rot, np.where(np.abs(pos - ipos).max(axis=-1) < SAME_FRAME_EPS, _INERTIA, _INERTIAROT), _NONE)


GEOMETRY_FIELDS = ("geom_pos", "geom_quat", "geom_aabb", "geom_rbound", "site_pos", "site_quat")
"""The geoms' and sites' fields :class:`GeomLayout` takes from the model (shared by every env)."""


class GeomLayout:
    """The geoms, sites and bounding-volume nodes of some bodies, with the values that
    depend only on them (the model's: :data:`GEOMETRY_FIELDS` shared by every env).

    Args:
        model: the scene model.
        bodies: the body ids.
    """

    def __init__(self, model: mujoco.MjModel, bodies: np.ndarray):
        self.geoms, self.geom_owner = _members(model.body_geomadr, model.body_geomnum, bodies)
        self.sites = np.flatnonzero(np.isin(model.site_bodyid, bodies))
        site_owner = np.searchsorted(bodies, model.site_bodyid[self.sites])
        self.rotated = {}  # kind -> (ids, owners, pos, quat) of elements whose class follows the inertial frame
        for kind, ids, owner in (("geom", self.geoms, self.geom_owner), ("site", self.sites, site_owner)):
            pos, quat = getattr(model, f"{kind}_pos")[ids], getattr(model, f"{kind}_quat")[ids]
            keep = ~null_quat(quat)
            self.rotated[kind] = (ids[keep], owner[keep], pos[keep], quat[keep])
        gpos, gquat, rbound = model.geom_pos[self.geoms], model.geom_quat[self.geoms], model.geom_rbound[self.geoms]
        reach = rbound > 0
        self.reach_owner, self.reach_pos, self.reach_rbound = self.geom_owner[reach], gpos[reach], rbound[reach]
        self.reach_slots = _slots(self.reach_owner, len(bodies))
        self.bvh = _Bvh(model, bodies, self.geoms, self.geom_owner, gpos, gquat, model.geom_aabb[self.geoms])

    def sizes(self, ipos: np.ndarray, com_dist: np.ndarray) -> np.ndarray:
        """``(n, nbody)`` body sizes (the rotational ``dof_length``): the largest of the
        centre of mass's distance to the joint and, per geom, its bounding radius plus its
        distance to the centre of mass."""
        d = ipos[:, self.reach_owner] - self.reach_pos
        reach = self.reach_rbound + np.sqrt(d[..., 0] ** 2 + d[..., 1] ** 2 + d[..., 2] ** 2)
        slots = self.reach_slots
        if slots.shape[1] == 1 and (slots >= 0).all():
            size = reach[:, slots[:, 0]]
        else:
            size = np.where(slots >= 0, reach[:, np.maximum(slots, 0)], 0.0).max(axis=-1, initial=0.0)
        return np.maximum(np.maximum(size, com_dist), _MIN_SIZE)


class _Bvh:
    """Bounding-volume nodes: leaves (one geom each) and inner nodes by depth, deepest
    first, so children are boxed before their parent."""

    def __init__(
        self,
        model: mujoco.MjModel,
        bodies: np.ndarray,
        geoms: np.ndarray,
        geom_owner: np.ndarray,
        gpos: np.ndarray,
        gquat: np.ndarray,
        gaabb: np.ndarray,
    ):
        column = {int(g): i for i, g in enumerate(geoms)}
        nodes: list[int] = []
        leaves: list[int] = []
        leaf_geoms: list[int] = []
        levels: dict[int, list[tuple[int, list[int]]]] = {}  # depth -> (inner node, its two children)
        for b in bodies:
            for node in range(model.body_bvhadr[b], model.body_bvhadr[b] + model.body_bvhnum[b]):
                nodes.append(node)
                if model.bvh_nodeid[node] >= 0:
                    leaves.append(node)
                    leaf_geoms.append(column[int(model.bvh_nodeid[node])])  # a global geom id
                else:  # children are numbered from the body's first node
                    kids = [int(model.body_bvhadr[b] + c) for c in model.bvh_child[node] if c >= 0]
                    levels.setdefault(int(model.bvh_depth[node]), []).append((node, kids * (3 - len(kids))))
        self.nodes = np.asarray(nodes, dtype=np.int64)
        col = {node: i for i, node in enumerate(nodes)}
        self.leaf_cols = np.asarray([col[n] for n in leaves], dtype=np.int64)
        g = np.asarray(leaf_geoms, dtype=np.int64)
        self.leaf_owner = geom_owner[g]
        geom_rot = quat_to_mat(gquat[g])
        self.leaf_rot, self.leaf_half = geom_rot, gaabb[g, 3:, None]
        self.leaf_centre = gpos[g] + (geom_rot @ gaabb[g, :3, None])[..., 0]  # box centre, body frame
        self.inner = [
            (
                np.asarray([col[n] for n, _ in levels[d]], dtype=np.int64),
                np.asarray([[col[c] for c in kids[:2]] for _, kids in levels[d]], dtype=np.int64),
            )
            for d in sorted(levels, reverse=True)
        ]

    def boxes(self, rot: np.ndarray, ipos: np.ndarray) -> np.ndarray:
        """``(n, nodes, 6)`` centre and half-size of every node in its body's inertial frame,
        for bodies with inertial frames ``rot`` ``(n, nbody, 3, 3)`` and ``ipos``."""
        frame = rot[:, self.leaf_owner]
        centre = ((self.leaf_centre - ipos[:, self.leaf_owner])[..., None, :] @ frame)[..., 0, :]
        half = (np.abs(np.swapaxes(frame, -1, -2) @ self.leaf_rot) @ self.leaf_half)[..., 0]
        out = np.empty((max(len(centre), len(half)), len(self.nodes), 6))
        out[:, self.leaf_cols, :3] = centre
        out[:, self.leaf_cols, 3:] = half
        for cols, children in self.inner:
            kids = out[:, children]  # (n, k, 2, 6)
            low = (kids[..., :3] - kids[..., 3:]).min(axis=2)
            high = (kids[..., :3] + kids[..., 3:]).max(axis=2)
            out[:, cols, :3] = (low + high) / 2
            out[:, cols, 3:] = (high - low) / 2
        return out


def _members(adr: np.ndarray, num: np.ndarray, bodies: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Element ids (geoms) of ``bodies`` in order, and the index of each one's body."""
    ids = [np.arange(adr[b], adr[b] + num[b]) for b in bodies]
    if not ids:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    owner = [np.full(len(i), k) for k, i in enumerate(ids)]
    return np.concatenate(ids).astype(np.int64), np.concatenate(owner).astype(np.int64)


def _slots(owner: np.ndarray, nb: int) -> np.ndarray:
    """``(nb, max members)`` member indices per body, padded with -1."""
    width = max([int((owner == k).sum()) for k in range(nb)] + [1])
    slots = -np.ones((nb, width), dtype=np.int64)
    for k in range(nb):
        members = np.flatnonzero(owner == k)
        slots[k, : len(members)] = members
    return slots
