"""Rotations and rigid transforms: the one implementation of the project.

Conventions (MuJoCo's):

- quaternions are ``(..., 4)`` ``(w, x, y, z)``; a quaternion made from a matrix has ``w >= 0``;
- rotation matrices are ``(..., 3, 3)`` and act on column vectors;
- Euler angles are extrinsic x-y-z (scipy ``"xyz"``, MuJoCo ``eulerseq="XYZ"``: rotate about
  the fixed x, then y, then z axis), in degrees unless ``degrees=False``;
- a pose7 is ``(..., 7)`` position xyz + quaternion wxyz; a pose matrix is ``(..., 4, 4)``.

Array flavours: every function takes numpy arrays (float arrays keep their dtype, other
array-likes become float64) or torch tensors (any float dtype and device, batched over the
leading dimensions), and returns the flavour and dtype it was given.

Design: each function is written once, over the namespace ``xp`` of its input (``numpy`` or
``torch``, through names both share); three helpers (:func:`_split`, :func:`_stack`,
:func:`_const`) pick each library's fast form. Torch tensors on the CPU (float32/64, no
autograd) run the same code on zero-copy numpy views (:func:`_numpy_views`; numpy has less
overhead per operation on the small batches of this project); CUDA tensors and tensors that
require grad run in torch. Rotation matrices are one matrix product of the quaternion's outer
product with a constant table.

Dtype exceptions: :func:`euler_xyz_to_quat` always returns float64; :func:`matrix_to_quat`
computes in float64 and returns the input dtype. On numpy, ``matrix_to_quat`` equals
``mju_mat2Quat`` (then flipped to ``w >= 0``) and ``euler_xyz_to_quat`` equals
``mju_euler2Quat(q, radians, "XYZ")`` bit for bit.

Example:
    >>> q = euler_xyz_to_quat(torch.tensor([[0.0, 90.0, 0.0]]))
    >>> quat_to_matrix(q).shape
    torch.Size([1, 3, 3])
    >>> matrix_to_quat(np.eye(3))
    array([1., 0., 0., 0.])
"""

from __future__ import annotations

import functools
import math
from typing import Any, Callable, Optional, Sequence, TypeVar, Union, overload

import numpy as np
import torch

Array = TypeVar("Array", np.ndarray, torch.Tensor)
"""A numpy array or a torch tensor; functions return the flavour they were given."""

ArrayLike = Union[np.ndarray, torch.Tensor, Sequence[Any]]
"""What a function reads: a numpy array, a torch tensor or a (nested) sequence of numbers."""

__all__ = [
    "transform_inverse",
    "quat_mul",
    "quat_conjugate",
    "quat_normalize",
    "quat_rotate",
    "quat_to_matrix",
    "matrix_to_quat",
    "euler_xyz_to_quat",
    "quat_to_euler_xyz",
    "pose_to_matrix",
    "matrix_to_pose",
    "as_pose7",
    "pose_mul",
    "pose_inverse",
    "compose_frames",
    "init_quat_from_cfg",
    "init_pos_from_cfg",
]

_F = TypeVar("_F", bound=Callable[..., Any])
_VIEWABLE = frozenset((torch.float32, torch.float64))
#: Whether CPU tensors take the numpy fast path (the device audit turns it off, so that on
#: the CPU the functions run the torch code a GPU runs:
#: :class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit`).
NUMPY_VIEWS = True


def _numpy_views(fn: _F) -> _F:
    """Run ``fn`` on numpy views of CPU tensors (float32/64, no grad) and return tensors."""

    @functools.wraps(fn)
    def run(*args: Any, **kwargs: Any) -> Any:
        if not NUMPY_VIEWS or isinstance(args[0], np.ndarray) or not isinstance(args[0], torch.Tensor):
            return fn(*args, **kwargs)
        tensors = [a for a in args if isinstance(a, torch.Tensor)]
        if not all(t.is_cpu and not t.requires_grad and t.dtype in _VIEWABLE for t in tensors):
            return fn(*args, **kwargs)
        out = fn(*(a.numpy() if isinstance(a, torch.Tensor) else a for a in args), **kwargs)
        return tuple(map(torch.from_numpy, out)) if isinstance(out, tuple) else torch.from_numpy(out)

    return run  # type: ignore[return-value]


def _ns(x: Any) -> tuple[Any, Any]:
    """``(namespace, array)``: torch for tensors; numpy otherwise (non-float input as float64)."""
    if isinstance(x, np.ndarray) and x.dtype.kind == "f":
        return np, x
    if isinstance(x, torch.Tensor):
        return torch, x
    return np, np.asarray(x, dtype=np.float64)


def _like(xp: Any, x: Any, ref: Any) -> Any:
    """A second operand ``x`` in the flavour of ``ref`` (and on its device)."""
    if xp is np:
        return x if isinstance(x, np.ndarray) and x.dtype.kind == "f" else np.asarray(x, dtype=ref.dtype)
    return x if isinstance(x, torch.Tensor) else torch.as_tensor(np.asarray(x), dtype=ref.dtype, device=ref.device)


def _split(x: Any) -> list[Any]:
    """The components along the last axis."""
    return list(x.unbind(-1)) if isinstance(x, torch.Tensor) else [x[..., i] for i in range(x.shape[-1])]


def _stack(xp: Any, parts: Sequence[Any]) -> Any:
    """Same-shape, same-dtype ``parts`` stacked on a new last axis (numpy: written into one allocation)."""
    if xp is torch:
        return torch.stack(tuple(parts), dim=-1)
    out = np.empty(parts[0].shape + (len(parts),), dtype=parts[0].dtype)
    for i, part in enumerate(parts):
        out[..., i] = part
    return out


def _zeros(xp: Any, like: Any, shape: tuple[int, ...]) -> Any:
    return np.zeros(shape, dtype=like.dtype) if xp is np else like.new_zeros(shape)


_W, _X, _Y, _Z = range(4)


def _quat_to_matrix_table() -> np.ndarray:
    """``(16, 9)``: the entries of ``R - I`` as a linear map of the quaternion's outer product."""
    entries = (
        ((_Y, _Y, -2), (_Z, _Z, -2)),
        ((_X, _Y, 2), (_W, _Z, -2)),
        ((_X, _Z, 2), (_W, _Y, 2)),
        ((_X, _Y, 2), (_W, _Z, 2)),
        ((_X, _X, -2), (_Z, _Z, -2)),
        ((_Y, _Z, 2), (_W, _X, -2)),
        ((_X, _Z, 2), (_W, _Y, -2)),
        ((_Y, _Z, 2), (_W, _X, 2)),
        ((_X, _X, -2), (_Y, _Y, -2)),
    )
    out = np.zeros((16, 9))
    for entry, terms in enumerate(entries):
        for a, b, coef in terms:
            out[4 * a + b, entry] = coef
    return out


def _matrix_to_quat_table() -> np.ndarray:
    """``(9, 16)``: the symmetric 4 x 4 table of sums and differences of matrix entries that
    MuJoCo divides by the largest quaternion component (row k: the others when k is largest)."""
    pairs = {
        (_W, _X): ((7, 1), (5, -1)),
        (_W, _Y): ((2, 1), (6, -1)),
        (_W, _Z): ((3, 1), (1, -1)),
        (_X, _Y): ((1, 1), (3, 1)),
        (_X, _Z): ((2, 1), (6, 1)),
        (_Y, _Z): ((5, 1), (7, 1)),
    }
    out = np.zeros((9, 16))
    for (i, j), terms in pairs.items():
        for entry, coef in terms:
            out[entry, 4 * i + j] = out[entry, 4 * j + i] = coef
    return out


_TABLES: dict[str, np.ndarray] = {
    "quat_to_matrix": _quat_to_matrix_table(),
    "eye9": np.eye(3).reshape(9),
    "matrix_to_quat": _matrix_to_quat_table(),
    # 4 w^2, 4 x^2, 4 y^2, 4 z^2 = 1 + signs[0] m00 + signs[1] m11 + signs[2] m22 (columns w, x, y, z)
    "signs": np.array([[1.0, 1.0, -1.0, -1.0], [1.0, -1.0, 1.0, -1.0], [1.0, -1.0, -1.0, 1.0]]),
    "arange4": np.arange(4.0),
}
_CONSTS: dict[tuple[Any, ...], Any] = {}


def _const(xp: Any, name: str, like: Any) -> Any:
    """The table ``name`` in the dtype (and on the device) of ``like``, cached."""
    key = (name, like.dtype, None if xp is np else like.device)
    out = _CONSTS.get(key)
    if out is None:
        table = _TABLES[name]
        out = table.astype(like.dtype) if xp is np else torch.as_tensor(table, dtype=like.dtype, device=like.device)
        _CONSTS[key] = out
    return out


@_numpy_views
def quat_mul(a: Array, b: Array) -> Array:
    """Hamilton product ``a * b`` of ``(..., 4)`` quaternions (``mju_mulQuat``).

    Example:
        >>> quat_mul(np.array([1.0, 0, 0, 0]), np.array([0.0, 1, 0, 0]))
        array([0., 1., 0., 0.])
    """
    xp, a = _ns(a)
    b = _like(xp, b, a)
    (aw, ax, ay, az), (bw, bx, by, bz) = _split(a), _split(b)
    return _stack(
        xp,
        (
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ),
    )


@_numpy_views
def quat_conjugate(q: Array) -> Array:
    """Conjugate of ``(..., 4)`` quaternions, the inverse of unit ones (``mju_negQuat``).

    Example:
        >>> quat_conjugate(np.array([1.0, 2, 3, 4]))
        array([ 1., -2., -3., -4.])
    """
    xp, q = _ns(q)
    out = -q
    out[..., 0] = q[..., 0]
    return out


@_numpy_views
def quat_normalize(q: Array) -> Array:
    """``(..., 4)`` quaternions scaled to unit norm.

    Example:
        >>> quat_normalize(np.array([2.0, 0, 0, 0]))
        array([1., 0., 0., 0.])
    """
    xp, q = _ns(q)
    return q / xp.sqrt(xp.sum(q * q, -1, keepdims=True))


@_numpy_views
def quat_rotate(q: Array, v: Array) -> Array:
    """``(..., 3)`` vectors ``v`` rotated by unit quaternions ``q`` (``mju_rotVecQuat``).

    Example:
        >>> quat_rotate(euler_xyz_to_quat([0.0, 0.0, 90.0]), [1.0, 0.0, 0.0]).round(6)
        array([0., 1., 0.])
    """
    xp, q = _ns(q)
    v = _like(xp, v, q)
    return (quat_to_matrix(q) @ v[..., None])[..., 0]


@_numpy_views
def quat_to_matrix(q: Array) -> Array:
    """``(..., 4)`` unit quaternions to ``(..., 3, 3)`` rotation matrices (``mju_quat2Mat``).

    The quaternion is not normalized here (see :func:`quat_normalize`).

    Example:
        >>> quat_to_matrix(torch.tensor([1.0, 0.0, 0.0, 0.0])).diagonal()
        tensor([1., 1., 1.])
    """
    xp, q = _ns(q)
    batch = tuple(q.shape[:-1])
    outer = (q[..., :, None] * q[..., None, :]).reshape(batch + (16,))
    entries = outer @ _const(xp, "quat_to_matrix", q) + _const(xp, "eye9", q)  # 1 - 2 (y y + z z), ...
    return entries.reshape(batch + (3, 3))


@_numpy_views
def matrix_to_quat(m: Array) -> Array:
    """``(..., 3, 3)`` rotation matrices to ``(..., 4)`` unit quaternions with ``w >= 0``.

    Solves for the largest of w, x, y, z and normalizes, as ``mju_mat2Quat`` (bit for bit
    on numpy), in float64; the result has the input's dtype.

    Example:
        >>> matrix_to_quat(np.diag([1.0, -1.0, -1.0]))  # 180 degrees about x
        array([0., 1., 0., 0.])
    """
    xp, m = _ns(m)
    dtype, batch = m.dtype, tuple(m.shape[:-2])
    m = (m.to(torch.float64) if isinstance(m, torch.Tensor) else m.astype(np.float64, copy=False)).reshape(batch + (9,))
    m00, m11, m22 = m[..., 0], m[..., 4], m[..., 8]
    largest = xp.where(m00 + m11 + m22 > 0, 0, xp.where((m00 > m11) & (m00 > m22), 1, xp.where(m11 > m22, 2, 3)))
    pick = largest[..., None] == _const(xp, "arange4", m)  # one-hot: w, x, y or z is the largest
    signs = _const(xp, "signs", m)
    squares = ((1 + m00[..., None] * signs[0]) + m11[..., None] * signs[1]) + m22[..., None] * signs[2]
    big = 0.5 * xp.sqrt((squares * pick).sum(-1, keepdims=True))  # the largest component
    others = ((m @ _const(xp, "matrix_to_quat", m)).reshape(batch + (4, 4)) * pick[..., None]).sum(-2)
    q = xp.where(pick, big, 0.25 * others / big)
    norm = xp.sqrt((q * q).sum(-1, keepdims=True))
    q = xp.where(abs(norm - 1) > 1e-15, q / norm, q)  # as MuJoCo: near-unit results stay as they are
    q = xp.where(q[..., :1] < 0, -q, q)
    return q.to(dtype) if xp is torch else q.astype(dtype, copy=False)


@overload
def euler_xyz_to_quat(euler: torch.Tensor, degrees: bool = True) -> torch.Tensor: ...
@overload
def euler_xyz_to_quat(euler: Union[np.ndarray, Sequence[Any]], degrees: bool = True) -> np.ndarray: ...
@_numpy_views
def euler_xyz_to_quat(euler: ArrayLike, degrees: bool = True) -> Union[np.ndarray, torch.Tensor]:
    """``(..., 3)`` extrinsic x-y-z Euler angles to ``(..., 4)`` float64 quaternions.

    The product ``qz * qy * qx``, rounded as ``mju_euler2Quat(q, radians, "XYZ")``.

    Example:
        >>> euler_xyz_to_quat([0.0, 0.0, 90.0]).round(4)
        array([0.7071, 0.    , 0.    , 0.7071])
    """
    xp, e = _ns(euler)
    e = e.to(torch.float64) if xp is torch else e.astype(np.float64, copy=False)
    half = e * (math.pi / 360.0 if degrees else 0.5)  # the same bits as (e * pi / 180) / 2
    if xp is np and half.ndim == 2 and not half[:, :2].any():  # yaw only (spawn draws): qz, the same values
        out = np.zeros(half.shape[:-1] + (4,))
        out[:, 0], out[:, 3] = np.cos(half[:, 2]), np.sin(half[:, 2])
        return out
    (cx, cy, cz), (sx, sy, sz) = _split(xp.cos(half)), _split(xp.sin(half))
    tw, tx, ty, tz = cy * cx, cy * sx, sy * cx, sy * sx  # qy * qx, with tz its negated z
    return _stack(xp, (cz * tw + sz * tz, cz * tx - sz * ty, cz * ty + sz * tx, sz * tw - cz * tz))


@_numpy_views
def quat_to_euler_xyz(q: Array, degrees: bool = True) -> Array:
    """``(..., 4)`` unit quaternions to extrinsic x-y-z Euler angles (the inverse of
    :func:`euler_xyz_to_quat`, with y in [-90, 90] degrees).

    Example:
        >>> quat_to_euler_xyz(euler_xyz_to_quat([10.0, 20.0, 30.0])).round(6)
        array([10., 20., 30.])
    """
    xp, q = _ns(q)
    r = quat_to_matrix(q)
    x = xp.atan2(r[..., 2, 1], r[..., 2, 2])
    y = xp.asin(xp.clip(-r[..., 2, 0], -1.0, 1.0))
    z = xp.atan2(r[..., 1, 0], r[..., 0, 0])
    e = _stack(xp, (x, y, z))
    return e * (180.0 / math.pi) if degrees else e


@_numpy_views
def pose_to_matrix(pose: Array) -> Array:
    """``(..., 7)`` xyz + wxyz poses to ``(..., 4, 4)`` homogeneous matrices.

    Example:
        >>> pose_to_matrix(np.array([1.0, 2, 3, 1, 0, 0, 0]))[:3, 3]
        array([1., 2., 3.])
    """
    xp, pose = _ns(pose)
    out = _zeros(xp, pose, tuple(pose.shape[:-1]) + (4, 4))
    out[..., :3, :3] = quat_to_matrix(pose[..., 3:7])
    out[..., :3, 3] = pose[..., :3]
    out[..., 3, 3] = 1.0
    return out


@_numpy_views
def matrix_to_pose(mat: Array) -> Array:
    """``(..., 4, 4)`` homogeneous matrices to ``(..., 7)`` xyz + wxyz poses (``w >= 0``).

    Example:
        >>> matrix_to_pose(np.eye(4))
        array([0., 0., 0., 1., 0., 0., 0.])
    """
    xp, mat = _ns(mat)
    return xp.concatenate((mat[..., :3, 3], matrix_to_quat(mat[..., :3, :3])), axis=-1)


def as_pose7(pose: Array) -> Array:
    """``(N, 7)`` poses from ``(N, 7)`` or ``(N, 4, 4)`` ones.

    Example:
        >>> as_pose7(torch.eye(4)[None]).shape
        torch.Size([1, 7])
    """
    if tuple(pose.shape[-2:]) == (4, 4):
        return matrix_to_pose(pose)
    if pose.shape[-1] != 7:
        raise ValueError(f"expected poses of shape (N, 7) or (N, 4, 4), got {tuple(pose.shape)}")
    return pose


@_numpy_views
def pose_mul(a: Array, b: Array) -> Array:
    """Pose7 ``b`` (given in frame ``a``) in the frame ``a`` is given in (``mju_mulPose``).

    Example:
        >>> pose_mul(np.array([1.0, 0, 0, 1, 0, 0, 0]), np.array([0.0, 1, 0, 1, 0, 0, 0]))
        array([1., 1., 0., 1., 0., 0., 0.])
    """
    xp, a = _ns(a)
    b = _like(xp, b, a)
    pos = a[..., :3] + quat_rotate(a[..., 3:7], b[..., :3])
    return xp.concatenate((pos, quat_mul(a[..., 3:7], b[..., 3:7])), axis=-1)


@_numpy_views
def pose_inverse(pose: Array) -> Array:
    """Inverse of ``(..., 7)`` poses with unit quaternions (``mju_negPose``).

    Example:
        >>> pose_inverse(np.array([1.0, 2, 3, 1, 0, 0, 0]))
        array([-1., -2., -3.,  1., -0., -0., -0.])
    """
    xp, pose = _ns(pose)
    quat = quat_conjugate(pose[..., 3:7])
    return xp.concatenate((-quat_rotate(quat, pose[..., :3]), quat), axis=-1)


def transform_inverse(transform: torch.Tensor) -> torch.Tensor:
    """Inverse of ``(..., 4, 4)`` rigid transforms: the rotation transposed, no general
    matrix inverse (a LAPACK call, slow on busy threads, and a host sync on some devices).

    Example:
        >>> t = torch.eye(4); t[:3, 3] = torch.tensor([1.0, 2.0, 3.0])
        >>> transform_inverse(t)[:3, 3]
        tensor([-1., -2., -3.])
    """
    out = torch.zeros_like(transform)
    rot_t = transform[..., :3, :3].transpose(-1, -2)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -(rot_t @ transform[..., :3, 3:4])[..., 0]
    out[..., 3, 3] = 1.0
    return out


@_numpy_views
def compose_frames(pos_a: Array, rot_a: Array, pos_b: Array, rot_b: Array) -> tuple[Array, Array]:
    """Frame ``b`` (position and rotation matrix, given in frame ``a``) in the frame ``a`` is given in.

    Example:
        >>> pos, rot = compose_frames(np.zeros(3), np.eye(3), np.ones(3), np.eye(3))
        >>> pos
        array([1., 1., 1.])
    """
    xp, pos_a = _ns(pos_a)
    rot_a, pos_b, rot_b = (_like(xp, x, pos_a) for x in (rot_a, pos_b, rot_b))
    return pos_a + (rot_a @ pos_b[..., None])[..., 0], rot_a @ rot_b


def init_quat_from_cfg(init_rot: Sequence[float], init_local_pose: Optional[Any] = None) -> np.ndarray:
    """Quaternion (w, x, y, z) of an object's configured initial orientation (numpy float64).

    Example:
        >>> init_quat_from_cfg([0.0, 0.0, 0.0])
        array([1., 0., 0., 0.])
    """
    if init_local_pose is not None:
        return matrix_to_quat(np.asarray(init_local_pose, dtype=np.float64)[:3, :3])
    return euler_xyz_to_quat(np.asarray(init_rot, dtype=np.float64))


def init_pos_from_cfg(init_pos: Sequence[float], init_local_pose: Optional[Any] = None) -> np.ndarray:
    """Position of an object's configured initial pose (numpy float64, a copy).

    Example:
        >>> init_pos_from_cfg([1.0, 2.0, 3.0])
        array([1., 2., 3.])
    """
    if init_local_pose is not None:
        return np.asarray(init_local_pose, dtype=np.float64)[:3, 3].copy()
    return np.asarray(init_pos, dtype=np.float64).copy()
