"""Object observations ``f(env, obs, **params) -> value``: poses, velocities and scales of
scene entities in the env frame, and the position of a task target."""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject

from embodichain_functors._common import ParamError, entity_of, validated
from embodichain_functors.randomization.geometry import body_scale_factor

__all__ = [
    "get_object_pose",
    "get_rigid_object_pose",
    "get_rigid_object_velocity",
    "get_object_body_scale",
    "target_position",
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


#: The param naming the env attribute it reads (checked against the writers at build).
target_position.reads_env_key = "target_pose_key"  # type: ignore[attr-defined]
