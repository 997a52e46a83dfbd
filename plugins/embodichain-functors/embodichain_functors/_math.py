"""Small batched rotation helpers in numpy (float64), for the hot paths of the functors.

Quaternions are (w, x, y, z); Euler angles are extrinsic x-y-z (as the core's
``euler_xyz_to_quat``).
"""

from __future__ import annotations

import numpy as np


def euler_to_quat(euler: np.ndarray, degrees: bool = True) -> np.ndarray:
    """(n, 3) extrinsic x-y-z Euler angles to (n, 4) quaternions (``qz * qy * qx``)."""
    half = np.asarray(euler, dtype=np.float64) * (np.pi / 360.0 if degrees else 0.5)
    if half.ndim == 2 and not half[:, :2].any():  # yaw only (the common case): qz
        out = np.zeros((half.shape[0], 4))
        out[:, 0], out[:, 3] = np.cos(half[:, 2]), np.sin(half[:, 2])
        return out
    c, s = np.cos(half), np.sin(half)
    cx, cy, cz = c.T
    sx, sy, sz = s.T
    cycz, sysz, sycz, cysz = cy * cz, sy * sz, sy * cz, cy * sz
    out = np.empty(half.shape[:-1] + (4,))
    out[..., 0] = cx * cycz + sx * sysz
    out[..., 1] = sx * cycz - cx * sysz
    out[..., 2] = cx * sycz + sx * cysz
    out[..., 3] = cx * cysz - sx * sycz
    return out


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (..., 4) quaternions."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack((aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw), axis=-1)


def pose_to_matrix(pose: np.ndarray) -> np.ndarray:
    """(n, 7) xyz + wxyz poses to (n, 4, 4) homogeneous matrices."""
    w, x, y, z = pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * x, y * y, z * z, x * y, x * z, y * z, w * x, w * y, w * z
    out = np.zeros((pose.shape[0], 4, 4))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = 1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = 2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = 2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)
    out[:, :3, 3] = pose[:, :3]
    out[:, 3, 3] = 1.0
    return out