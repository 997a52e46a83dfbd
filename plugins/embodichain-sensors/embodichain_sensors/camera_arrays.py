"""Array helpers of the camera sensors: output buffers, tensors on the output device, poses
as tensors, and the MuJoCo camera added to the spec for each view."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.utils.math import matrix_to_quat


def _alloc(key: str, n: int, h: int, w: int) -> np.ndarray:
    if key == "color":
        out = np.empty((n, h, w, 4), dtype=np.uint8)
        out[..., 3] = 255
        return out
    return np.empty((n, h, w), dtype=np.int32 if key == "mask" else np.float32)


def _trailing(arr: Any, dims: int) -> Any:
    return arr[..., None] if dims else arr


def _host(arr: Any) -> np.ndarray:
    """A numpy array of ``arr`` (a tensor is copied from its device)."""
    return arr.detach().cpu().numpy() if isinstance(arr, torch.Tensor) else arr


def _tensor(arr: Any, device: torch.device) -> torch.Tensor:
    """``arr`` as a contiguous tensor on ``device``."""
    if isinstance(arr, torch.Tensor):
        return arr.to(device).contiguous()
    return torch.from_numpy(np.ascontiguousarray(arr)).to(device)


def _pose_out(pos: np.ndarray, rot: np.ndarray, to_matrix: bool) -> torch.Tensor:
    if to_matrix:
        mat = np.zeros(pos.shape[:-1] + (4, 4))
        mat[..., :3, :3], mat[..., :3, 3], mat[..., 3, 3] = rot, pos, 1.0
        return torch.from_numpy(mat.astype(np.float32))
    return torch.from_numpy(np.concatenate([pos, matrix_to_quat(rot)], axis=-1).astype(np.float32))


def _add_spec_camera(
    body: Any, name: str, pos: np.ndarray, rot: np.ndarray, intr: np.ndarray, width: int, height: int
) -> None:
    """A MuJoCo camera matching the sensor (for viewers and ``mujoco.Renderer``).

    MuJoCo's ``principal_pixel`` is the offset of the image centre from the
    principal point, measured with y up (checked on MuJoCo 4.0).
    """
    fx, fy, cx, cy = (float(v) for v in intr)
    cam = body.add_camera(name=name, pos=pos, quat=matrix_to_quat(rot))
    cam.resolution = [width, height]
    cam.sensor_size = [width * 1e-5, height * 1e-5]
    cam.focal_pixel = [fx, fy]
    cam.principal_pixel = [width / 2.0 - (cx + 0.5), height / 2.0 - (cy + 0.5)]
