"""A camera's view poses computed on the simulation's device, for the Warp renderer.

The renderer writes every world's camera frames on the device. Composing them there from the
mount body's pose in MuJoCo Warp's state (``sim.xpos`` / ``sim.xmat``), the camera's local
pose and each view's offset keeps the step free of host round trips: the constant parts are
copied to the device once, and again only after :meth:`DevicePoses.invalidate` (the camera
calls it from ``set_local_pose`` and ``look_at``).

Example:
    >>> poses = DevicePoses()                      # doctest: +SKIP
    >>> [(pos, rot)] = poses(camera)  # (N, 3), (N, 3, 3) float32 on the sim's device  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import torch

from embodichain_core.utils.math import compose_frames

__all__ = ["DevicePoses", "mount_poses_on_device"]


def mount_poses_on_device(mount: Any, sim: Any, offset: Optional[tuple]) -> tuple[torch.Tensor, torch.Tensor]:
    """``(N, 3)`` positions and ``(N, 3, 3)`` rotations of ``mount``'s frame, read from the
    sim's state views on its device; ``offset`` is the mount's ``(pos, rot)`` in its body on
    that device (None: the body frame itself)."""
    xpos = sim.xpos[:, mount.body_id]
    xmat = sim.xmat[:, mount.body_id].reshape(-1, 3, 3)
    if offset is None:
        return xpos, xmat
    pos, rot = offset
    return xpos + xmat @ pos, xmat @ rot


class DevicePoses:
    """Per view ``(pos (N, 3), rot (N, 3, 3))`` in the env frame, float32 on the sim's device."""

    def __init__(self) -> None:
        self._consts: Optional[dict[str, Any]] = None

    def invalidate(self) -> None:
        """Copy the camera's local pose and the view offsets to the device again at the next call."""
        self._consts = None

    def __call__(self, camera: Any) -> list[tuple[torch.Tensor, torch.Tensor]]:
        sim = camera.scene.sim
        consts = self._consts
        if consts is None:
            consts = self._consts = _upload(camera, sim.device)
        rig = compose_frames(*mount_poses_on_device(camera.mount, sim, consts["mount"]), *consts["local"])
        return [rig if view is None else compose_frames(*rig, *view) for view in consts["views"]]


def _upload(camera: Any, device: torch.device) -> dict[str, Any]:
    """The constant terms of the camera's view poses as float32 tensors on ``device``."""

    def on(*arrays: np.ndarray) -> tuple[torch.Tensor, ...]:
        return tuple(torch.as_tensor(np.asarray(a, dtype=np.float32), device=device) for a in arrays)

    mount = camera.mount
    at_body = mount.body is None or (not mount.pos.any() and np.array_equal(mount.rot, np.eye(3)))
    return {
        "mount": None if at_body else on(mount.pos, mount.rot),
        "local": on(camera._local_pos, camera._local_rot),
        "views": [None if v.is_identity else on(v.pos, v.rot) for v in camera.views],
    }
