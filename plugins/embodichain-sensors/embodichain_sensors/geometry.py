"""Pose and projection math of the camera sensors (numpy, float64, batched).

Rotations are ``(..., 3, 3)`` matrices; quaternions ``(w, x, y, z)``. Camera
frames follow OpenGL/MuJoCo: columns of a camera rotation are its +X (right),
+Y (up) and +Z (backwards; the camera looks along -Z).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """``(..., 4)`` quaternions (normalized here) to ``(..., 3, 3)`` rotations."""
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    rows = [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]
    return np.stack(rows, axis=-1).reshape(q.shape[:-1] + (3, 3))


def mat_to_quat(m: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)`` rotations to ``(..., 4)`` unit quaternions with ``w >= 0``."""
    m = np.asarray(m, dtype=np.float64)
    flat = m.reshape(-1, 3, 3)
    out = np.empty((flat.shape[0], 4))
    for i, r in enumerate(flat):
        out[i] = _mat_to_quat_one(r)
    out[out[:, 0] < 0] *= -1
    return out.reshape(m.shape[:-2] + (4,))


def _mat_to_quat_one(r: np.ndarray) -> np.ndarray:
    """Shepperd's method for one rotation matrix."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    return q / np.linalg.norm(q)


def euler_xyz_deg_to_mat(euler: Sequence[float]) -> np.ndarray:
    """Extrinsic x-y-z Euler angles in degrees (scipy ``"xyz"``) to a rotation."""
    ax, ay, az = np.radians(np.asarray(euler, dtype=np.float64))
    rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Camera position and rotation (OpenGL camera frame) looking from ``eye`` at ``target``.

    Args:
        eye, target: ``(..., 3)`` points; ``up``: ``(..., 3)``, default +z. When
            ``up`` is parallel to the view direction, +y (or +x) is used instead.

    Returns:
        ``(pos (..., 3), rot (..., 3, 3))``.
    """
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    up = np.broadcast_to(np.asarray((0.0, 0.0, 1.0) if up is None else up, dtype=np.float64), eye.shape)
    forward = target - eye
    norm = np.linalg.norm(forward, axis=-1, keepdims=True)
    if np.any(norm < 1e-12):
        raise ValueError("look_at: eye and target must differ")
    forward = forward / norm
    right = np.cross(forward, up)
    for fallback in ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0)):
        bad = np.linalg.norm(right, axis=-1) < 1e-9
        if not np.any(bad):
            break
        right = np.where(bad[..., None], np.cross(forward, np.asarray(fallback)), right)
    right = right / np.linalg.norm(right, axis=-1, keepdims=True)
    cam_up = np.cross(right, forward)
    rot = np.stack([right, cam_up, -forward], axis=-1)
    return eye.copy(), rot


def compose(pos_a: np.ndarray, rot_a: np.ndarray, pos_b: np.ndarray, rot_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Frame ``b`` (given in frame ``a``) in the frame ``a`` is given in."""
    pos = pos_a + (rot_a @ pos_b[..., None])[..., 0]
    return pos, rot_a @ rot_b


def intrinsic_matrix(intrinsics: np.ndarray) -> np.ndarray:
    """``(..., 4)`` ``(fx, fy, cx, cy)`` to ``(..., 3, 3)`` matrices."""
    intr = np.asarray(intrinsics, dtype=np.float64)
    k = np.zeros(intr.shape[:-1] + (3, 3))
    k[..., 0, 0], k[..., 1, 1] = intr[..., 0], intr[..., 1]
    k[..., 0, 2], k[..., 1, 2], k[..., 2, 2] = intr[..., 2], intr[..., 3], 1.0
    return k


def frustum(intrinsics: Sequence[float], width: int, height: int, near: float) -> tuple[float, float, float, float]:
    """OpenGL frustum ``(center, half_width, bottom, top)`` at distance ``near`` that
    reproduces the OpenCV pixel projection ``u = fx x / z + cx`` exactly.

    Pixel ``u`` covers ``[u - 0.5, u + 0.5]``, so the image spans ``[-0.5, W - 0.5]``.
    MuJoCo's renderer takes the horizontal extent as ``center +- half_width``.
    """
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    left, right = -(cx + 0.5) * near / fx, (width - 0.5 - cx) * near / fx
    bottom, top = -(height - 0.5 - cy) * near / fy, (cy + 0.5) * near / fy
    return 0.5 * (left + right), 0.5 * (right - left), bottom, top


def project(points_cam: np.ndarray, intrinsics: Sequence[float]) -> np.ndarray:
    """Pixels ``(..., 2)`` of points given in the OpenGL camera frame ``(..., 3)``."""
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    p = np.asarray(points_cam, dtype=np.float64)
    z = -p[..., 2]
    return np.stack([fx * p[..., 0] / z + cx, -fy * p[..., 1] / z + cy], axis=-1)


def depth_to_points(depth: np.ndarray, intrinsics: Sequence[float]) -> np.ndarray:
    """Per-pixel points ``(..., H, W, 3)`` in the OpenGL camera frame from z-depth ``(..., H, W)``."""
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    h, w = depth.shape[-2:]
    u = (np.arange(w, dtype=np.float32) - cx) / fx
    v = (cy - np.arange(h, dtype=np.float32)) / fy
    return np.stack([depth * u[None, :], depth * v[:, None], -depth], axis=-1).astype(np.float32)


def points_to_normals(points: np.ndarray) -> np.ndarray:
    """Unit normals ``(..., H, W, 3)`` facing the camera, from per-pixel points
    (central differences; zero where the surface is undefined)."""
    du = np.gradient(points, axis=-2)
    dv = np.gradient(points, axis=-3)
    n = np.cross(dv, du)
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.divide(n, norm, out=np.zeros_like(n), where=norm > 1e-12)
    flip = np.sum(n * points, axis=-1, keepdims=True) > 0
    return np.where(flip, -n, n).astype(np.float32)
