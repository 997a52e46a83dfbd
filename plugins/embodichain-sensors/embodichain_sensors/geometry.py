"""Camera frames and projection math of the camera sensors (numpy, float64, batched).

Rotations are ``(..., 3, 3)`` matrices. Camera frames follow OpenGL/MuJoCo: columns of a
camera rotation are its +X (right), +Y (up) and +Z (backwards; the camera looks along -Z).
Quaternion, Euler and frame-composition maths come from :mod:`embodichain_core.utils.math`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


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
