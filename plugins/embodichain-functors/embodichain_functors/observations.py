"""Observation functors: ``add`` functors ``f(env, obs, **params) -> value`` and the
``modify`` functor ``normalize_robot_joint_data(env, data, **params) -> new data``.

Example:
    >>> import embodichain_functors.observations as obs
    >>> ObservationCfg(func=obs.get_rigid_object_pose, mode="add", name="fork_pose",
    ...                params={"entity_cfg": SceneEntityCfg(uid="fork")})
"""

from __future__ import annotations

import builtins
from typing import Any, Optional, Sequence

import torch

from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject

from embodichain_functors._common import ParamError, as_range, entity_of, validated
from embodichain_functors._kinematics import check_ik, check_part, default_part, eef_pose
from embodichain_functors.observation_functors.physics import (
    get_articulation_joint_drive,
    get_rigid_object_physics_attributes,
)
from embodichain_functors.observation_functors.sensors import (
    compute_semantic_mask,
    get_sensor_intrinsics,
    get_sensor_pose_in_robot_frame,
)
from embodichain_functors.randomization.geometry import body_scale_factor

__all__ = [
    "get_object_pose", "get_rigid_object_pose", "get_rigid_object_velocity", "get_object_body_scale",
    "normalize_robot_joint_data", "get_robot_eef_pose", "get_sensor_pose_in_robot_frame", "get_sensor_intrinsics",
    "target_position", "compute_semantic_mask", "get_rigid_object_physics_attributes",
    "get_articulation_joint_drive",
]


def _check_object_pose(env: Any, entity_cfg: Any, to_matrix: bool = True) -> None:
    entity = env.scene.get(entity_cfg.uid)
    if not (callable(getattr(entity, "get_local_pose", None)) or callable(getattr(entity, "get_arena_pose", None))):
        raise ParamError("get_object_pose", "entity_cfg", f"{entity_cfg.uid!r} has no pose")


@validated(_check_object_pose)
def get_object_pose(env: Any, obs: Any, entity_cfg: Any, to_matrix: bool = True) -> torch.Tensor:
    """Pose of any entity in the env frame: (N, 4, 4), or (N, 7) xyz + wxyz.

    Rigid objects, articulations (root link), groups ((N, K, ...)) and sensors.

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the entity.
        to_matrix: 4x4 matrices (else xyz + wxyz).

    Example:
        ``{"func": "get_object_pose", "mode": "add", "name": "object/drawer_pose",
        "params": {"entity_cfg": {"uid": "drawer"}, "to_matrix": false}}``
    """
    entity = env.scene[entity_cfg.uid]
    if callable(getattr(entity, "get_local_pose", None)) and not hasattr(entity, "get_arena_pose"):
        return entity.get_local_pose(to_matrix=to_matrix)
    return entity.get_arena_pose(to_matrix=to_matrix)


def _check_rigid(functor: str) -> Any:
    def check(env: Any, entity_cfg: Any, **_: Any) -> None:
        entity_of(env, entity_cfg, functor, (RigidObject, RigidObjectGroup))
    return check


@validated(_check_rigid("get_rigid_object_pose"))
def get_rigid_object_pose(env: Any, obs: Any, entity_cfg: Any, to_matrix: bool = True) -> torch.Tensor:
    """Pose of a rigid object (or group): (N, 4, 4), or (N, 7) xyz + wxyz with ``to_matrix=False``.

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the rigid object.
        to_matrix: 4x4 matrices (else xyz + wxyz).

    Example:
        ``{"func": "get_rigid_object_pose", "mode": "add", "name": "fork_pose",
        "params": {"entity_cfg": {"uid": "fork"}}}``
    """
    return env.scene[entity_cfg.uid].get_local_pose(to_matrix=to_matrix)


@validated(_check_rigid("get_rigid_object_velocity"))
def get_rigid_object_velocity(env: Any, obs: Any, entity_cfg: Any) -> torch.Tensor:
    """World-frame (N, 6) linear + angular velocity of a rigid object (zeros if kinematic).

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the rigid object.

    Example:
        ``{"func": "get_rigid_object_velocity", "mode": "add", "name": "object/cube_vel",
        "params": {"entity_cfg": {"uid": "cube"}}}``
    """
    return env.scene[entity_cfg.uid].get_velocity()


def _check_scale(env: Any, entity_cfg: Any) -> None:
    entity_of(env, entity_cfg, "get_object_body_scale", (RigidObject,))


@validated(_check_scale)
def get_object_body_scale(env: Any, obs: Any, entity_cfg: Any) -> torch.Tensor:
    """(N, 3) body scale of a rigid object (per env after ``randomize_rigid_object_scale``).

    The configured ``body_scale`` times the per-env factor of the scale randomization.

    Args:
        env: the env.
        obs: the observation (unused).
        entity_cfg: the rigid object.

    Example:
        ``{"func": "get_object_body_scale", "mode": "add", "name": "object/cube_scale",
        "params": {"entity_cfg": {"uid": "cube"}}}``
    """
    obj = env.scene[entity_cfg.uid]
    return (obj.body_scale.double() * body_scale_factor(obj)).float()


def _check_normalize(env: Any, joint_ids: Optional[Sequence[int]] = None, limit: str = "qpos_limits",
                     range: Sequence[float] = (0.0, 1.0)) -> None:
    name = "normalize_robot_joint_data"
    if limit not in ("qpos_limits", "qvel_limits"):
        raise ParamError(name, "limit", f"must be 'qpos_limits' or 'qvel_limits', got {limit!r}")
    as_range(range, name, "range")
    n = len(env.active_joint_ids)
    if joint_ids is not None and any(not 0 <= int(j) < n for j in joint_ids):
        raise ParamError(name, "joint_ids", f"indices into the {n} active joints, got {list(joint_ids)}")


@validated(_check_normalize)
def normalize_robot_joint_data(env: Any, data: torch.Tensor, joint_ids: Optional[Sequence[int]] = None,
                               limit: str = "qpos_limits", range: Sequence[float] = (0.0, 1.0)) -> torch.Tensor:
    """(modify) Map joint data from the robot's limits to ``range`` (returns a new tensor).

    Args:
        env: the env.
        data: (N, n_active) joint data (``robot/qpos`` or ``robot/qvel``).
        joint_ids: columns to normalize (indices into the active joints; all by default).
        limit: ``"qpos_limits"`` (lower..upper) or ``"qvel_limits"`` (-max..max).
        range: target ``[low, high]``.

    Example:
        ``{"func": "normalize_robot_joint_data", "mode": "modify", "name": "robot/qpos",
        "params": {"joint_ids": [0, 1, 2, 3, 4, 5, 6]}}``
    """
    cols = list(builtins.range(data.shape[-1])) if joint_ids is None else [int(j) for j in joint_ids]
    active = torch.as_tensor(env.active_joint_ids, dtype=torch.long)[cols]
    if limit == "qpos_limits":
        lim = env.robot.get_qpos_limits()[:, active]
        low, high = lim[..., 0], lim[..., 1]
    else:
        high = env.robot.get_qvel_limits()[:, active]
        low = -high
    out = data.clone()
    span = (high - low).clamp_min(1e-12)
    out[:, cols] = range[0] + (data[:, cols] - low) / span * (range[1] - range[0])
    return out


def _check_eef(env: Any, part_name: Optional[str] = None, position_only: bool = False) -> None:
    check_part(env.robot, part_name, "get_robot_eef_pose", "part_name")
    check_ik(env.robot, default_part(env, env.robot, part_name), "get_robot_eef_pose", "part_name")


@validated(_check_eef)
def get_robot_eef_pose(env: Any, obs: Any, part_name: Optional[str] = None,
                       position_only: bool = False) -> torch.Tensor:
    """End-effector pose of a control part by forward kinematics: (N, 4, 4) or (N, 3).

    Args:
        env: the env.
        obs: the observation (unused).
        part_name: the control part (the env's first control part by default).
        position_only: only the (N, 3) position.

    Example:
        ``{"func": "get_robot_eef_pose", "mode": "add", "name": "robot/ee_pose", "params": {"part_name": "arm"}}``
    """
    pose = eef_pose(env.robot, default_part(env, env.robot, part_name))
    return pose[:, :3, 3].clone() if position_only else pose


def target_position(env: Any, obs: Any, target_pose_key: str = "goal_pose") -> torch.Tensor:
    """(N, 3) target position read from ``env.<target_pose_key>`` ((N, 3) or (N, 4, 4)); zeros before it exists.

    Args:
        env: the env.
        obs: the observation (unused).
        target_pose_key: env attribute holding the targets (set by ``randomize_target_pose``).

    Example:
        ``{"func": "target_position", "mode": "add", "name": "task/goal", "params": {"target_pose_key": "goal_pose"}}``
    """
    target = getattr(env, target_pose_key, None)
    if target is None:
        return torch.zeros(env.num_envs, 3)
    target = torch.as_tensor(target, dtype=torch.float32)
    return target[:, :3, 3].clone() if target.dim() == 3 else target[:, :3].clone()
