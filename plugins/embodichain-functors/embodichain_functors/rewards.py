"""Reward functors ``f(env, obs, action, info, **params) -> (N,)``.

The stateful ones (``incremental_distance_to_target``, ``action_smoothness_penalty``)
are class functors whose state is cleared for the envs being reset.

Example:
    >>> import embodichain_functors.rewards as rewards
    >>> RewardCfg(func=rewards.distance_to_target, weight=0.8,
    ...           params={"source_entity_cfg": SceneEntityCfg(uid="cube"), "target_pose_key": "goal_pose"})
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import torch

from embodichain_core.sim.entities.robot import Robot

from embodichain_functors._common import ParamError, check_positive, validated
from embodichain_functors._kinematics import check_ik, default_part, eef_pose
from embodichain_functors.reward_functors import (
    action_smoothness_penalty,
    incremental_distance_to_target,
    position_of,
    rotation_of,
    target_positions,
)

__all__ = [
    "distance_between_objects", "distance_to_target", "incremental_distance_to_target", "joint_velocity_penalty",
    "joint_limit_penalty", "action_smoothness_penalty", "orientation_alignment", "reaching_behind_object",
    "success_reward",
]


def _check_entities(functor: str, *keys: str) -> Any:
    def check(env: Any, **params: Any) -> None:
        for key in keys:
            cfg = params.get(key)
            if cfg is not None and getattr(cfg, "uid", None) not in env.scene:
                raise ParamError(functor, key, f"no entity {getattr(cfg, 'uid', cfg)!r} in the scene")
        if "sigma" in params:
            check_positive(params["sigma"], functor, "sigma")
    return check


def _shape(d: torch.Tensor, exponential: bool, sigma: float) -> torch.Tensor:
    return torch.exp(-(d ** 2) / (2.0 * sigma ** 2)) if exponential else -d


@validated(_check_entities("distance_between_objects", "source_entity_cfg", "target_entity_cfg"), lead=3)
def distance_between_objects(env: Any, obs: Any, action: Any, info: dict, source_entity_cfg: Any,
                             target_entity_cfg: Any, exponential: bool = False, sigma: float = 1.0) -> torch.Tensor:
    """``-d`` (or ``exp(-d^2 / 2 sigma^2)``) of the distance between two entities.

    A robot entity with ``control_parts`` uses that part's end effector.

    Args:
        env: the env.
        obs, action, info: step data (unused).
        source_entity_cfg: the first entity.
        target_entity_cfg: the second entity.
        exponential: the Gaussian kernel instead of the negative distance.
        sigma: kernel width in metres.

    Example:
        ``{"func": "distance_between_objects", "weight": 0.5, "params": {"source_entity_cfg": {"uid": "cube"},
        "target_entity_cfg": {"uid": "plate"}, "exponential": true, "sigma": 0.1}}``
    """
    d = (position_of(env, source_entity_cfg) - position_of(env, target_entity_cfg)).norm(dim=-1)
    return _shape(d, exponential, sigma)


@validated(_check_entities("distance_to_target", "source_entity_cfg"), lead=3)
def distance_to_target(env: Any, obs: Any, action: Any, info: dict, source_entity_cfg: Any,
                       target_pose_key: str = "target_pose", exponential: bool = False, sigma: float = 1.0,
                       use_xy_only: bool = False) -> torch.Tensor:
    """``-d`` (or ``exp(-d^2 / 2 sigma^2)``) of an entity's distance to ``env.<target_pose_key>``.

    Args:
        env: the env.
        obs, action, info: step data (unused).
        source_entity_cfg: the entity.
        target_pose_key: env attribute with the targets ((N, 3), (N, 7) or (N, 4, 4)); a missing one raises.
        exponential: the Gaussian kernel instead of the negative distance.
        sigma: kernel width in metres.
        use_xy_only: ignore z.

    Example:
        ``{"func": "distance_to_target", "weight": 0.8, "params": {"source_entity_cfg": {"uid": "cube"},
        "target_pose_key": "goal_pose", "exponential": true, "sigma": 0.12, "use_xy_only": true}}``
    """
    delta = position_of(env, source_entity_cfg) - target_positions(env, target_pose_key, "distance_to_target")
    d = (delta[:, :2] if use_xy_only else delta).norm(dim=-1)
    return _shape(d, exponential, sigma)


def _robot(env: Any, robot_uid: Optional[str]) -> Robot:
    return env.robot if robot_uid is None else env.scene[robot_uid]


def _check_robot(functor: str) -> Any:
    def check(env: Any, robot_uid: Optional[str] = None, part_name: Optional[str] = None, **_: Any) -> None:
        if robot_uid is not None and robot_uid not in env.scene.robots:
            raise ParamError(functor, "robot_uid", f"no robot {robot_uid!r} (robots: {list(env.scene.robots)})")
        robot = _robot(env, robot_uid)
        if part_name is not None and part_name not in (robot.control_parts or {}):
            raise ParamError(functor, "part_name", f"robot {robot.uid!r} has no control part {part_name!r}")
    return check


def _joints(robot: Robot, joint_ids: Any, part_name: Optional[str]) -> Any:
    if joint_ids is not None:
        return joint_ids if isinstance(joint_ids, slice) else list(joint_ids)
    return robot.get_joint_ids(part_name) if part_name else slice(None)


@validated(_check_robot("joint_velocity_penalty"), lead=3)
def joint_velocity_penalty(env: Any, obs: Any, action: Any, info: dict, robot_uid: Optional[str] = None,
                           joint_ids: Optional[Sequence[int]] = None, part_name: Optional[str] = None) -> torch.Tensor:
    """``-||qvel||`` of a robot's joints (``joint_ids`` win over ``part_name``; all joints by default).

    Args:
        env: the env.
        obs, action, info: step data (unused).
        robot_uid: the robot (the env's robot by default).
        joint_ids: robot joint ids.
        part_name: a control part.

    Example:
        ``{"func": "joint_velocity_penalty", "weight": 0.005, "params": {"part_name": "arm"}}``
    """
    robot = _robot(env, robot_uid)
    return -robot.get_qvel()[:, _joints(robot, joint_ids, part_name)].norm(dim=-1)


@validated(_check_robot("joint_limit_penalty"), lead=3)
def joint_limit_penalty(env: Any, obs: Any, action: Any, info: dict, robot_uid: Optional[str] = None,
                        joint_ids: Any = None, margin: float = 0.1) -> torch.Tensor:
    """Sum over joints of ``-(margin - dist)`` where the normalized distance to a limit is below ``margin``.

    Distances are fractions of each joint's range; unlimited joints never count.

    Args:
        env: the env.
        obs, action, info: step data (unused).
        robot_uid: the robot (the env's robot by default).
        joint_ids: robot joint ids (all by default).
        margin: fraction of the range near each limit that is penalized.

    Example:
        ``{"func": "joint_limit_penalty", "weight": 0.1, "params": {"margin": 0.05}}``
    """
    robot = _robot(env, robot_uid)
    cols = _joints(robot, joint_ids, None)
    q, lim = robot.get_qpos()[:, cols], robot.get_qpos_limits()[:, cols]
    span = lim[..., 1] - lim[..., 0]
    finite = torch.isfinite(span) & (span > 0)
    span = torch.where(finite, span, torch.ones_like(span))
    dist = torch.minimum(q - lim[..., 0], lim[..., 1] - q) / span
    return -((margin - dist).clamp_min(0.0) * finite).sum(dim=-1)


@validated(_check_entities("orientation_alignment", "source_entity_cfg", "target_entity_cfg"), lead=3)
def orientation_alignment(env: Any, obs: Any, action: Any, info: dict, source_entity_cfg: Any,
                          target_entity_cfg: Any) -> torch.Tensor:
    """``(trace(R_s R_t^T) - 1) / 2`` in [-1, 1]: 1 when two entities are aligned.

    Args:
        env: the env.
        obs, action, info: step data (unused).
        source_entity_cfg: the first entity.
        target_entity_cfg: the second entity.

    Example:
        ``{"func": "orientation_alignment", "weight": 0.2, "params": {"source_entity_cfg": {"uid": "cup"},
        "target_entity_cfg": {"uid": "plate"}}}``
    """
    rs, rt = rotation_of(env, source_entity_cfg), rotation_of(env, target_entity_cfg)
    trace = (rs * rt).sum(dim=(-2, -1))  # trace(R_s R_t^T)
    return ((trace - 1.0) / 2.0).clamp(-1.0, 1.0)


def success_reward(env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
    """1 where ``info["success"]``, else 0 (0 everywhere when the key is missing).

    Args:
        env: the env.
        obs, action: step data (unused).
        info: the step info.

    Example:
        ``{"func": "success_reward", "weight": 10.0}``
    """
    success = info.get("success") if isinstance(info, dict) else None
    if success is None:
        return torch.zeros(env.num_envs)
    return torch.as_tensor(success).reshape(-1).float().expand(env.num_envs).clone()


def _check_behind(env: Any, object_cfg: Any, part_name: Optional[str] = None, distance_scale: float = 5.0,
                  **_: Any) -> None:
    if getattr(object_cfg, "uid", None) not in env.scene:
        raise ParamError("reaching_behind_object", "object_cfg", f"no entity {object_cfg!r} in the scene")
    check_positive(distance_scale, "reaching_behind_object", "distance_scale")
    _check_robot("reaching_behind_object")(env, part_name=part_name)
    check_ik(env.robot, default_part(env, env.robot, part_name), "reaching_behind_object", "part_name")


@validated(_check_behind, lead=3)
def reaching_behind_object(env: Any, obs: Any, action: Any, info: dict, object_cfg: Any,
                           target_pose_key: str = "goal_pose", behind_offset: float = 0.015,
                           height_offset: float = 0.015, distance_scale: float = 5.0,
                           part_name: Optional[str] = None) -> torch.Tensor:
    """``1 - tanh(s * ||ee - p||)``: reach the point behind the object, seen from the goal.

    ``p = obj - behind_offset * dir_xy(obj -> goal) + height_offset * z``, so pushing
    from there moves the object towards the goal.

    Args:
        env: the env.
        obs, action, info: step data (unused).
        object_cfg: the object to push.
        target_pose_key: env attribute with the goals (a missing one raises).
        behind_offset: distance behind the object (metres).
        height_offset: height above the object's centre (metres).
        distance_scale: ``s``.
        part_name: the robot's control part (the env's first by default).

    Example:
        ``{"func": "reaching_behind_object", "weight": 0.03, "params": {"object_cfg": {"uid": "cube"},
        "target_pose_key": "goal_pose"}}``
    """
    obj = position_of(env, object_cfg)
    goal = target_positions(env, target_pose_key, "reaching_behind_object")
    direction = torch.zeros_like(obj)
    direction[:, :2] = goal[:, :2] - obj[:, :2]
    direction = direction / direction.norm(dim=-1, keepdim=True).clamp_min(1e-9)
    point = obj - behind_offset * direction
    point[:, 2] += height_offset
    ee = eef_pose(env.robot, default_part(env, env.robot, part_name))[:, :3, 3]
    return 1.0 - torch.tanh(distance_scale * (ee - point).norm(dim=-1))
