"""A camera sensor's poses and intrinsics: its views, its pose in its parent frame, where it
sits in the env frame, and the API that reads and sets them (a mixin of
:class:`~embodichain_sensors.camera.Camera`, whose stereo subclass adds a second view).

The pose in the parent frame (``set_local_pose``, ``look_at``) is per env on the host; the
env-frame poses follow the mount link's current pose (:meth:`CameraPoses.get_view_poses`, and
on the device :class:`~embodichain_sensors.device_poses.DevicePoses` for the Warp renderer,
told here when the local pose changes).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from embodichain_core.sim.entities.base import env_index
from embodichain_core.utils.math import compose_frames, quat_normalize, quat_to_matrix
from embodichain_sensors import geometry as geo
from embodichain_sensors.camera_arrays import _pose_out

__all__ = ["CameraPoses", "View"]


@dataclass
class View:
    """One rendered viewpoint of a sensor: output key ``suffix``, per-env
    ``intrinsics (N, 4)``, its pose in the sensor (rig) frame, its spec camera."""

    suffix: str
    intrinsics: np.ndarray
    pos: np.ndarray
    rot: np.ndarray
    camera: str = ""
    camera_id: int = -1

    @property
    def is_identity(self) -> bool:
        """The view is the sensor frame itself (a mono camera)."""
        return not self.pos.any() and np.array_equal(self.rot, np.eye(3))


class CameraPoses:
    """Pose and intrinsics state and API; the sensor sets ``cfg``, ``num_envs``, ``scene``,
    ``mount``, ``views`` and ``_device_poses``."""

    cfg: Any
    num_envs: int
    scene: Any
    mount: Any
    views: list[View]
    _device_poses: Any
    _local_pos: np.ndarray  # (N, 3) in the parent frame
    _local_rot: np.ndarray  # (N, 3, 3)

    def _initial_local_pose(self) -> tuple[np.ndarray, np.ndarray]:
        ext = self.cfg.extrinsics
        if ext.eye is not None:
            pos, rot = geo.look_at(
                np.asarray(ext.eye), np.asarray(ext.target), None if ext.up is None else np.asarray(ext.up)
            )
        else:
            pos, rot = np.asarray(ext.pos, dtype=np.float64), quat_to_matrix(quat_normalize(np.asarray(ext.quat)))
        n = self.num_envs
        return np.repeat(pos[None], n, 0), np.repeat(rot[None], n, 0)

    def get_view_poses(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per view, ``(pos (N, 3), rot (N, 3, 3))`` in the env frame (current state)."""
        mpos, mrot = self.mount.body_poses(self.scene.sim)
        rig = compose_frames(mpos, mrot, self._local_pos, self._local_rot)
        return [rig if v.is_identity else compose_frames(*rig, v.pos, v.rot) for v in self.views]

    def get_arena_pose(self, to_matrix: bool = False) -> torch.Tensor:
        """The camera (rig) pose in the env frame: ``(N, 7)`` (xyz, wxyz) or ``(N, 4, 4)``."""
        mpos, mrot = self.mount.body_poses(self.scene.sim)
        return _pose_out(*compose_frames(mpos, mrot, self._local_pos, self._local_rot), to_matrix)

    def get_local_pose(self, to_matrix: bool = False) -> torch.Tensor:
        """The camera pose in its parent frame (the env frame without a parent)."""
        return _pose_out(self._local_pos, self._local_rot, to_matrix)

    def set_local_pose(self, pose: Any, env_ids: Any = None) -> None:
        """Set the pose in the parent frame: ``(n, 7)`` (xyz, wxyz) or ``(n, 4, 4)``."""
        ids = env_index(env_ids, self.num_envs).cpu().numpy()
        p = np.asarray(pose.detach().cpu() if isinstance(pose, torch.Tensor) else pose, dtype=np.float64)
        if p.shape[-2:] == (4, 4):
            pos, rot = p[..., :3, 3], p[..., :3, :3]
        else:
            pos, rot = p[..., :3], quat_to_matrix(quat_normalize(p[..., 3:7]))
        self._local_pos[ids], self._local_rot[ids] = pos, rot
        self._device_poses.invalidate()

    def look_at(self, eye: Any, target: Any, up: Any = None, env_ids: Any = None) -> None:
        """Point the camera from ``eye`` at ``target`` (parent frame), for ``env_ids``."""
        ids = env_index(env_ids, self.num_envs).cpu().numpy()
        eye, target = (
            np.broadcast_to(np.asarray(eye, float), (len(ids), 3)),
            np.broadcast_to(np.asarray(target, float), (len(ids), 3)),
        )
        self._local_pos[ids], self._local_rot[ids] = geo.look_at(
            eye, target, None if up is None else np.asarray(up, float)
        )
        self._device_poses.invalidate()

    def get_intrinsics(self) -> torch.Tensor:
        """``(N, 3, 3)`` intrinsic matrices (float32)."""
        return torch.from_numpy(geo.intrinsic_matrix(self.views[0].intrinsics).astype(np.float32))

    def set_intrinsics(self, intrinsics: Any, env_ids: Any = None) -> None:
        """Set ``(fx, fy, cx, cy)`` (or ``(n, 3, 3)`` matrices) for ``env_ids``."""
        _set_intrinsics(self.views[0], intrinsics, env_index(env_ids, self.num_envs).cpu().numpy())


def _set_intrinsics(view: View, intrinsics: Any, ids: np.ndarray) -> None:
    k = np.asarray(intrinsics.detach().cpu() if isinstance(intrinsics, torch.Tensor) else intrinsics, dtype=np.float64)
    if k.shape[-2:] == (3, 3):
        k = np.stack([k[..., 0, 0], k[..., 1, 1], k[..., 0, 2], k[..., 1, 2]], axis=-1)
    if np.any(k[..., :2] <= 0):
        raise ValueError(f"fx and fy must be > 0, got {k.tolist()}")
    view.intrinsics[ids] = k
