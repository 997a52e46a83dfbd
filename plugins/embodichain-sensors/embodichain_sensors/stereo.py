"""``StereoCamera``: two cameras on one rig (EmbodiChain's ``StereoCameraCfg``).

The configured pose is the rig centre. The left camera is at
``-left_to_right_pos / 2`` in the rig frame; the right camera is at
``left_to_right_pos`` from the left one, rotated by ``left_to_right_rot``, in the
left camera's frame (so a pure x baseline puts the right camera to the right).
Both views are rendered from one ``mjv_updateScene`` per env.

Outputs follow EmbodiChain's table (note the trailing 1 of depth and mask):

=============================  ============================  ==============================
key                            dtype / shape                 meaning
=============================  ============================  ==============================
``color``, ``color_right``     uint8 ``(N, H, W, 4)``        RGBA
``depth``, ``depth_right``     float32 ``(N, H, W, 1)``      z-depth in metres
``mask``, ``mask_right``       int32 ``(N, H, W, 1)``        entity ids, -1 none
``normal(_right)``             float32 ``(N, H, W, 3)``      camera frame
``position(_right)``           float32 ``(N, H, W, 3)``      camera frame
``disparity``                  float32 ``(N, H, W, 1)``      ``fx * |baseline| / depth``
=============================  ============================  ==============================
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import torch

from embodichain_core.sim.entities.base import env_index
from embodichain_core.utils.math import euler_xyz_to_quat, quat_to_matrix
from embodichain_sensors import geometry as geo
from embodichain_sensors.camera import Camera
from embodichain_sensors.camera_arrays import _host, _pose_out
from embodichain_sensors.camera_poses import View, _set_intrinsics


class StereoCamera(Camera):
    """A stereo pair; ``get_data()`` has left outputs and ``*_right`` outputs."""

    image_dims = {"depth": 1, "mask": 1}

    def _make_views(self) -> list[View]:
        cfg, n = self.cfg, self.num_envs
        baseline = np.asarray(cfg.left_to_right_pos, dtype=np.float64)
        rot = quat_to_matrix(euler_xyz_to_quat(cfg.left_to_right_rot))
        left_pos = -0.5 * baseline
        left = View("", np.tile(np.asarray(cfg.intrinsics, dtype=np.float64), (n, 1)), left_pos, np.eye(3))
        right = View(
            "_right", np.tile(np.asarray(cfg.right_intrinsics(), dtype=np.float64), (n, 1)), left_pos + baseline, rot
        )
        return [left, right]

    @property
    def baseline(self) -> float:
        """Distance between the two camera centres (metres)."""
        return float(np.linalg.norm(self.cfg.left_to_right_pos))

    def _outputs(self, raw: dict[str, np.ndarray]) -> dict[str, torch.Tensor]:
        out = super()._outputs(raw)
        if self.cfg.enable_disparity:
            out["disparity"] = torch.from_numpy(self._disparity(_host(raw["depth"]))).to(self._out_device)
        return out

    def _disparity(self, depth: np.ndarray) -> np.ndarray:
        """``fx * |baseline| / depth`` from the left camera's configured fx; 0 where depth is 0."""
        fx = self.views[0].intrinsics[:, 0].astype(np.float32)[:, None, None]
        num = fx * np.float32(self.baseline)
        disp = np.divide(num, depth, out=np.zeros_like(depth), where=depth > 0)
        return disp[..., None]

    def get_intrinsics(self) -> tuple[torch.Tensor, torch.Tensor]:  # type: ignore[override]  # EmbodiChain's pair
        """``(left (N, 3, 3), right (N, 3, 3))`` intrinsic matrices (EmbodiChain's order)."""
        left, right = (geo.intrinsic_matrix(v.intrinsics).astype(np.float32) for v in self.views)
        return torch.from_numpy(left), torch.from_numpy(right)

    def set_intrinsics(  # type: ignore[override]  # EmbodiChain's signature: the right intrinsics second
        self, intrinsics: Any, intrinsics_right: Optional[Any] = None, env_ids: Any = None
    ) -> None:
        """Set the left (and right; default: the same) intrinsics for ``env_ids``."""
        ids = env_index(env_ids, self.num_envs).cpu().numpy()
        _set_intrinsics(self.views[0], intrinsics, ids)
        _set_intrinsics(self.views[1], intrinsics if intrinsics_right is None else intrinsics_right, ids)

    def get_left_right_arena_pose(self, to_matrix: bool = False) -> tuple[torch.Tensor, torch.Tensor]:
        """``(left, right)`` camera poses in the env frame, ``(N, 7)`` or ``(N, 4, 4)``."""
        (lp, lr), (rp, rr) = self.get_view_poses()
        return _pose_out(lp, lr, to_matrix), _pose_out(rp, rr, to_matrix)
