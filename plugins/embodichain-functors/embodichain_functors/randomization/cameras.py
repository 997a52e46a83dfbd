"""Camera randomization: additive perturbations of a camera's configured extrinsics and
intrinsics, per env.

Camera sensors (embodichain-sensors) render from their own per-env pose and
intrinsics, so the functors use the sensor's API (``set_local_pose``,
``look_at``, ``set_intrinsics``). A sensor without that API that owns a MuJoCo
camera named after its uid is perturbed through the per-env model fields
``cam_pos``/``cam_quat``/``cam_intrinsic`` instead.
"""

from __future__ import annotations

from typing import Any, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.utils.math import euler_xyz_to_quat, quat_mul

from embodichain_functors._common import ParamError, check_optional_range, env_ids_of, uniform, validated
from embodichain_functors._sim import write_model

VISUAL = "randomization.visual"
_POSE_KEYS = ("pos_range", "euler_range")
_LOOK_KEYS = ("eye_range", "target_range", "up_range")
_INTR_KEYS = ("focal_x_range", "focal_y_range", "cx_range", "cy_range")

__all__ = ["randomize_camera_extrinsics", "randomize_camera_intrinsics"]


def camera_sensor(env: Any, entity_cfg: Any, functor: str) -> Any:
    """The sensor named by ``entity_cfg`` (a camera)."""
    sensor = env.scene.sensors.get(getattr(entity_cfg, "uid", None))
    if sensor is None:
        raise ParamError(
            functor,
            "entity_cfg",
            f"{getattr(entity_cfg, 'uid', entity_cfg)!r} is not a sensor (sensors: {list(env.scene.sensors)})",
        )
    return sensor


def mj_camera(env: Any, uid: str) -> int:
    """Id of the MuJoCo camera named ``uid`` (``-1`` if none)."""
    return mujoco.mj_name2id(env.scene.model, mujoco.mjtObj.mjOBJ_CAMERA, uid)


def _look_at_mode(sensor: Any) -> bool:
    ext = getattr(sensor.cfg, "extrinsics", None)
    return ext is not None and getattr(ext, "eye", None) is not None


def _check_extrinsics(env: Any, entity_cfg: SceneEntityCfg, **ranges: Any) -> None:
    name = "randomize_camera_extrinsics"
    sensor = camera_sensor(env, entity_cfg, name)
    for key, value in ranges.items():
        check_optional_range(value, name, key, 3)
    given = [k for k, v in ranges.items() if v is not None]
    if not given:
        raise ParamError(name, "pos_range", f"give at least one of {list(_POSE_KEYS + _LOOK_KEYS)}")
    look = _look_at_mode(sensor)
    wrong = [k for k in given if k in (_POSE_KEYS if look else _LOOK_KEYS)]
    if wrong:
        mode = "look-at (eye/target/up)" if look else "offset (pos/quat, optionally attached to a parent)"
        raise ParamError(
            name,
            wrong[0],
            f"camera {entity_cfg.uid!r} uses {mode} extrinsics; use {list(_LOOK_KEYS if look else _POSE_KEYS)}",
        )
    api = "look_at" if look else "set_local_pose"
    if not callable(getattr(sensor, api, None)) and (look or mj_camera(env, entity_cfg.uid) < 0):
        raise ParamError(name, "entity_cfg", f"sensor {entity_cfg.uid!r} has neither {api}() nor a MuJoCo camera")


def _draw(env: Any, rng: Optional[Any], ids: torch.Tensor) -> torch.Tensor:
    return torch.zeros(len(ids), 3, dtype=torch.float64) if rng is None else uniform(env, ids, rng[0], rng[1])


@validated(_check_extrinsics)
def randomize_camera_extrinsics(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    pos_range: Any = None,
    euler_range: Any = None,
    eye_range: Any = None,
    target_range: Any = None,
    up_range: Any = None,
) -> None:
    """Perturb a camera's configured extrinsics per env (offsets from the configuration).

    Offset cameras (``pos``/``quat``, attached to a ``parent`` or not) take
    ``pos_range`` and ``euler_range``; look-at cameras take ``eye_range``,
    ``target_range`` and ``up_range``. Offsets are drawn around the configured
    values, so repeated calls do not drift.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the camera sensor.
        pos_range: ``[[dx, dy, dz] low, [...] high]`` added to ``extrinsics.pos`` (metres).
        euler_range: ``[[rx, ry, rz] low, [...] high]`` Euler degrees composed with ``extrinsics.quat``.
        eye_range: offsets of the look-at ``eye``.
        target_range: offsets of the look-at ``target``.
        up_range: offsets of the look-at ``up`` vector.

    Example:
        ``{"func": "randomize_camera_extrinsics", "mode": "reset", "params": {"entity_cfg": {"uid": "cam"},
        "eye_range": [[-0.05, -0.05, -0.05], [0.05, 0.05, 0.05]]}}``
    """
    ids = env_ids_of(env, env_ids)
    sensor = env.scene.sensors[entity_cfg.uid]
    ext = getattr(sensor.cfg, "extrinsics", None)
    if ext is not None and _look_at_mode(sensor):
        eye = np.asarray(ext.eye, dtype=np.float64) + _draw(env, eye_range, ids).numpy()
        target = np.asarray(ext.target, dtype=np.float64) + _draw(env, target_range, ids).numpy()
        up = np.asarray(ext.up if ext.up is not None else (0.0, 0.0, 1.0), dtype=np.float64)
        sensor.look_at(eye, target, up + _draw(env, up_range, ids).numpy(), env_ids=ids)
        return
    dpos, deuler = _draw(env, pos_range, ids), _draw(env, euler_range, ids)
    if callable(getattr(sensor, "set_local_pose", None)) and ext is not None:
        pos = torch.as_tensor(ext.pos, dtype=torch.float64) + dpos
        quat = quat_mul(torch.as_tensor(ext.quat, dtype=torch.float64).expand(len(ids), 4), euler_xyz_to_quat(deuler))
        sensor.set_local_pose(torch.cat((pos, quat), -1), env_ids=ids)
        return
    cam, model = mj_camera(env, entity_cfg.uid), env.scene.model
    quat = quat_mul(torch.as_tensor(model.cam_quat[cam]).expand(len(ids), 4), euler_xyz_to_quat(deuler))
    write_model(env.sim, ids, [("cam_pos", cam, torch.as_tensor(model.cam_pos[cam]) + dpos), ("cam_quat", cam, quat)])


def _check_intrinsics(env: Any, entity_cfg: SceneEntityCfg, **ranges: Any) -> None:
    name = "randomize_camera_intrinsics"
    sensor = camera_sensor(env, entity_cfg, name)
    for key, value in ranges.items():
        check_optional_range(value, name, key)
    if all(v is None for v in ranges.values()):
        raise ParamError(name, "focal_x_range", f"give at least one of {list(_INTR_KEYS)}")
    if not callable(getattr(sensor, "set_intrinsics", None)):
        cam = mj_camera(env, entity_cfg.uid)
        if cam < 0 or env.scene.model.cam_sensorsize[cam][0] <= 0:
            raise ParamError(
                name,
                "entity_cfg",
                f"sensor {entity_cfg.uid!r} has neither set_intrinsics() nor a MuJoCo camera with a sensor size",
            )


def _offsets(env: Any, ids: torch.Tensor, ranges: tuple) -> torch.Tensor:
    n = len(ids)
    zeros = torch.zeros(n, dtype=torch.float64)
    cols = [zeros if r is None else uniform(env, ids, r[0], r[1]).reshape(n) for r in ranges]
    return torch.stack(cols, -1)


@validated(_check_intrinsics)
def randomize_camera_intrinsics(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    focal_x_range: Any = None,
    focal_y_range: Any = None,
    cx_range: Any = None,
    cy_range: Any = None,
) -> None:
    """Add per-env offsets (pixels) to a camera's configured intrinsics ``(fx, fy, cx, cy)``.

    A stereo camera gets the same offsets on both views.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the camera sensor.
        focal_x_range: ``[low, high]`` offset of ``fx``.
        focal_y_range: ``[low, high]`` offset of ``fy``.
        cx_range: ``[low, high]`` offset of the principal point's ``cx``.
        cy_range: ``[low, high]`` offset of ``cy``.

    Example:
        ``{"func": "randomize_camera_intrinsics", "mode": "reset", "params": {"entity_cfg": {"uid": "cam"},
        "focal_x_range": [-20, 20], "focal_y_range": [-20, 20]}}``
    """
    ids = env_ids_of(env, env_ids)
    sensor = env.scene.sensors[entity_cfg.uid]
    delta = _offsets(env, ids, (focal_x_range, focal_y_range, cx_range, cy_range))
    if callable(getattr(sensor, "set_intrinsics", None)):
        left = torch.as_tensor(sensor.cfg.intrinsics, dtype=torch.float64) + delta
        right_of = getattr(sensor.cfg, "right_intrinsics", None)
        if callable(right_of):
            right = torch.as_tensor(right_of(), dtype=torch.float64) + delta
            sensor.set_intrinsics(left.numpy(), right.numpy(), env_ids=ids)
        else:
            sensor.set_intrinsics(left.numpy(), env_ids=ids)
        return
    cam, model = mj_camera(env, entity_cfg.uid), env.scene.model
    per_pixel = model.cam_sensorsize[cam] / model.cam_resolution[cam]
    scale = torch.as_tensor([per_pixel[0], per_pixel[1], -per_pixel[0], -per_pixel[1]])
    write_model(env.sim, ids, [("cam_intrinsic", cam, torch.as_tensor(model.cam_intrinsic[cam]) + delta * scale)])


randomize_camera_extrinsics.embodichain_category = VISUAL  # type: ignore[attr-defined]
randomize_camera_intrinsics.embodichain_category = VISUAL  # type: ignore[attr-defined]
