"""Sensor observations: camera poses in the robot frame, intrinsics, semantic masks.

They use the camera sensor's API (embodichain-sensors): ``get_arena_pose``,
``get_left_right_arena_pose``, ``get_intrinsics``, ``mask_id_of`` and, for the
robot-side mask channels, its renderer.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
import torch

from embodichain_functors._common import ParamError, validated
from embodichain_functors._functor import CheckedFunctor

__all__ = ["get_sensor_pose_in_robot_frame", "get_sensor_intrinsics", "compute_semantic_mask"]

BACKGROUND, FOREGROUND, ROBOT_LEFT, ROBOT_RIGHT = 0, 1, 2, 3


def _sensor(env: Any, entity_cfg: Any, functor: str, api: str) -> Any:
    sensor = env.scene.sensors.get(getattr(entity_cfg, "uid", None))
    if sensor is None or not callable(getattr(sensor, api, None)):
        raise ParamError(
            functor, "entity_cfg", f"{getattr(entity_cfg, 'uid', entity_cfg)!r} is not a camera sensor with {api}()"
        )
    return sensor


def _check_pose(env: Any, entity_cfg: Any, robot_uid: Optional[str] = None, is_right: bool = False) -> None:
    name = "get_sensor_pose_in_robot_frame"
    sensor = _sensor(env, entity_cfg, name, "get_arena_pose")
    if is_right and not callable(getattr(sensor, "get_left_right_arena_pose", None)):
        raise ParamError(name, "is_right", f"{entity_cfg.uid!r} is not a stereo camera")
    if robot_uid is not None and robot_uid not in env.scene.robots:
        raise ParamError(name, "robot_uid", f"no robot {robot_uid!r} (robots: {list(env.scene.robots)})")


@validated(_check_pose)
def get_sensor_pose_in_robot_frame(
    env: Any, obs: Any, entity_cfg: Any, robot_uid: Optional[str] = None, is_right: bool = False
) -> torch.Tensor:
    """(N, 4, 4) camera pose in the robot's base frame (stereo: left or right view).

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the camera sensor.
        robot_uid: the robot (the env's robot by default).
        is_right: the right view of a stereo camera.

    Example:
        ``{"func": "get_sensor_pose_in_robot_frame", "mode": "add", "name": "sensor/cam_pose",
        "params": {"entity_cfg": {"uid": "cam"}}}``
    """
    sensor = env.scene.sensors[entity_cfg.uid]
    if callable(getattr(sensor, "get_left_right_arena_pose", None)):
        cam = sensor.get_left_right_arena_pose(to_matrix=True)[1 if is_right else 0]
    else:
        cam = sensor.get_arena_pose(to_matrix=True)
    robot = env.robot if robot_uid is None else env.scene[robot_uid]
    base = robot.get_local_pose(to_matrix=True).double()
    return (torch.linalg.inv(base) @ cam.double()).float()


def _check_intrinsics(env: Any, entity_cfg: Any, is_right: bool = False) -> None:
    _sensor(env, entity_cfg, "get_sensor_intrinsics", "get_intrinsics")


@validated(_check_intrinsics)
def get_sensor_intrinsics(env: Any, obs: Any, entity_cfg: Any, is_right: bool = False) -> torch.Tensor:
    """(N, 3, 3) intrinsic matrix of a camera (stereo: left or right view).

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the camera sensor.
        is_right: the right view of a stereo camera.

    Example:
        ``{"func": "get_sensor_intrinsics", "mode": "add", "name": "sensor/cam_K",
        "params": {"entity_cfg": {"uid": "cam"}}}``
    """
    k = env.scene.sensors[entity_cfg.uid].get_intrinsics()
    if isinstance(k, (tuple, list)):
        k = k[1 if is_right else 0]
    return k.float()


class compute_semantic_mask(CheckedFunctor):
    """Boolean ``(N, H, W, 4)`` semantic mask of a camera: background, foreground, robot left, robot right.

    Robot sides are the links named ``left_*`` / ``right_*``.

    Foreground comes from the camera's ``mask`` output (``enable_mask=True``); unknown
    foreground uids are ignored. The robot channels need the robot's link split,
    which an entity mask cannot give: when the robot has ``left_*``/``right_*``
    links they are rendered once more per env with the camera's renderer.
    Background is the negation of the other three.

    Args (params):
        entity_cfg: the camera sensor (with ``enable_mask``).
        foreground_uids: uids of the foreground entities.
        is_right: the right view of a stereo camera.

    Example:
        ``{"func": "compute_semantic_mask", "mode": "add", "name": "sensor/cam/semantic",
        "params": {"entity_cfg": {"uid": "cam"}, "foreground_uids": ["cube"]}}``
    """

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._table = self._side_table(env)

    def check(
        self, env: Any, entity_cfg: Any = None, foreground_uids: Sequence[str] = (), is_right: bool = False
    ) -> None:
        name = type(self).__name__
        sensor = _sensor(env, entity_cfg, name, "mask_id_of")
        if not getattr(sensor.cfg, "enable_mask", False):
            raise ParamError(name, "entity_cfg", f"camera {entity_cfg.uid!r} needs enable_mask=True")
        if is_right and len(getattr(sensor, "views", [])) < 2:
            raise ParamError(name, "is_right", f"{entity_cfg.uid!r} is not a stereo camera")

    def _side_table(self, env: Any) -> Optional[np.ndarray]:
        """Geom -> channel (2 left, 3 right, -1 other), or ``None`` without side links."""
        model, robot = env.scene.model, env.robot
        table = np.full(model.ngeom, -1, dtype=np.int32)
        for link, body in zip(robot.link_names, robot.body_ids.tolist()):
            side = ROBOT_LEFT if link.startswith("left_") else ROBOT_RIGHT if link.startswith("right_") else -1
            table[model.geom_bodyid == body] = side
        return table if (table >= 0).any() else None

    def _render_sides(self, env: Any, sensor: Any, view: int, shape: tuple) -> np.ndarray:
        out = np.full(shape, -1, dtype=np.int32)
        renderer, sim = sensor.renderer, env.sim
        pos, rot = sensor.get_view_poses()[view]
        renderer.make_current()
        for i in range(env.num_envs):
            renderer.update_scene(sim.get_model(i), sim.get_data(i), sensor.views[0].camera_id)
            renderer.set_camera(pos[i], rot[i], sensor.views[view].intrinsics[i], sensor.cfg.near, sensor.cfg.far)
            out[i] = renderer.render_segmentation(self._table)[::-1]
        return out

    def __call__(
        self, env: Any, obs: Any, entity_cfg: Any, foreground_uids: Sequence[str] = (), is_right: bool = False
    ) -> torch.Tensor:
        sensor = env.scene.sensors[entity_cfg.uid]
        mask = obs["sensor"][entity_cfg.uid]["mask_right" if is_right else "mask"]
        mask = mask[..., 0] if mask.dim() == 4 else mask
        ids = [sensor.mask_id_of(u) for u in foreground_uids if u in sensor.mask_id_table.values()]
        out = torch.zeros(mask.shape + (4,), dtype=torch.bool)
        out[..., FOREGROUND] = torch.isin(mask, torch.tensor(ids, dtype=mask.dtype))
        if self._table is not None:
            sides = torch.from_numpy(self._render_sides(env, sensor, int(is_right), tuple(mask.shape)))
            out[..., ROBOT_LEFT], out[..., ROBOT_RIGHT] = sides == ROBOT_LEFT, sides == ROBOT_RIGHT
        out[..., BACKGROUND] = ~out[..., 1:].any(-1)
        return out
