"""Batched pose math on torch tensors. Quaternions are (w, x, y, z).

Example:
    >>> q = euler_xyz_to_quat(torch.tensor([[0.0, 90.0, 0.0]]), degrees=True)
    >>> quat_to_matrix(q).shape
    torch.Size([1, 3, 3])
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import torch


def _t(x: object, dtype: torch.dtype = torch.float32) -> torch.Tensor:
    return x.to(dtype) if isinstance(x, torch.Tensor) else torch.as_tensor(np.asarray(x), dtype=dtype)


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``a * b`` of (..., 4) quaternions."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack(
        (
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ),
        dim=-1,
    )


def quat_conjugate(q: torch.Tensor) -> torch.Tensor:
    """Inverse of unit quaternions."""
    return torch.cat((q[..., :1], -q[..., 1:]), dim=-1)


def quat_rotate(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate (..., 3) vectors ``v`` by unit quaternions ``q``."""
    w, xyz = q[..., :1], q[..., 1:]
    t = 2.0 * torch.cross(xyz, v, dim=-1)
    return v + w * t + torch.cross(xyz, t, dim=-1)


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """(..., 4) unit quaternions to (..., 3, 3) rotation matrices."""
    w, x, y, z = q.unbind(-1)
    rows = (
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    )
    return torch.stack(rows, dim=-1).reshape(q.shape[:-1] + (3, 3))


def matrix_to_quat(m: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) rotation matrices to (..., 4) unit quaternions (w >= 0)."""
    m = _t(m, m.dtype if isinstance(m, torch.Tensor) else torch.float32)
    shape = m.shape[:-2]
    flat = m.reshape(-1, 3, 3).detach().cpu().double().numpy()
    out = np.empty((flat.shape[0], 4))
    import mujoco

    for i, mat in enumerate(flat):
        mujoco.mju_mat2Quat(out[i], mat.reshape(-1))
    out[out[:, 0] < 0] *= -1
    return torch.as_tensor(out, dtype=m.dtype).reshape(shape + (4,))


def euler_xyz_to_quat(euler: torch.Tensor | Sequence[float], degrees: bool = True) -> torch.Tensor:
    """Extrinsic x-y-z Euler angles (scipy ``"xyz"``) to quaternions."""
    e = _t(euler, torch.float64)
    if degrees:
        e = e * (math.pi / 180.0)
    half = e / 2
    c, s = torch.cos(half), torch.sin(half)
    zeros = torch.zeros_like(c[..., 0])
    qx = torch.stack((c[..., 0], s[..., 0], zeros, zeros), -1)
    qy = torch.stack((c[..., 1], zeros, s[..., 1], zeros), -1)
    qz = torch.stack((c[..., 2], zeros, zeros, s[..., 2]), -1)
    return quat_mul(qz, quat_mul(qy, qx))


def quat_to_euler_xyz(q: torch.Tensor, degrees: bool = True) -> torch.Tensor:
    """Quaternions to extrinsic x-y-z Euler angles (inverse of :func:`euler_xyz_to_quat`)."""
    r = quat_to_matrix(q)
    x = torch.atan2(r[..., 2, 1], r[..., 2, 2])
    y = torch.asin(torch.clamp(-r[..., 2, 0], -1.0, 1.0))
    z = torch.atan2(r[..., 1, 0], r[..., 0, 0])
    e = torch.stack((x, y, z), -1)
    return e * (180.0 / math.pi) if degrees else e


def pose_to_matrix(pose: torch.Tensor) -> torch.Tensor:
    """(..., 7) xyz + wxyz poses to (..., 4, 4) homogeneous matrices."""
    out = torch.zeros(pose.shape[:-1] + (4, 4), dtype=pose.dtype, device=pose.device)
    out[..., :3, :3] = quat_to_matrix(pose[..., 3:7])
    out[..., :3, 3] = pose[..., :3]
    out[..., 3, 3] = 1.0
    return out


def matrix_to_pose(mat: torch.Tensor) -> torch.Tensor:
    """(..., 4, 4) homogeneous matrices to (..., 7) xyz + wxyz poses."""
    return torch.cat((mat[..., :3, 3], matrix_to_quat(mat[..., :3, :3])), dim=-1)


def as_pose7(pose: torch.Tensor) -> torch.Tensor:
    """Accept (N, 7) or (N, 4, 4) poses; return (N, 7)."""
    if pose.shape[-2:] == (4, 4):
        return matrix_to_pose(pose)
    if pose.shape[-1] != 7:
        raise ValueError(f"expected poses of shape (N, 7) or (N, 4, 4), got {tuple(pose.shape)}")
    return pose


def init_quat_from_cfg(init_rot: Sequence[float], init_local_pose: object = None) -> np.ndarray:
    """Quaternion (w, x, y, z) of an object's initial orientation, as numpy."""
    if init_local_pose is not None:
        mat = torch.as_tensor(np.asarray(init_local_pose, dtype=np.float64))
        return matrix_to_quat(mat[:3, :3]).numpy()
    return euler_xyz_to_quat(torch.as_tensor(init_rot, dtype=torch.float64)).numpy()


def init_pos_from_cfg(init_pos: Sequence[float], init_local_pose: object = None) -> np.ndarray:
    """Position of an object's initial pose, as numpy."""
    if init_local_pose is not None:
        return np.asarray(init_local_pose, dtype=np.float64)[:3, 3].copy()
    return np.asarray(init_pos, dtype=np.float64).copy()
