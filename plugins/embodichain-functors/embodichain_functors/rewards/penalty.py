"""Penalties ``f(env, obs, action, info, **params) -> (N,)``: joint velocities, joints near
their limits, and the change of the action between steps (per-env state, cleared on reset)."""

from __future__ import annotations

from typing import Any, Optional, Sequence

import torch

from embodichain_core.sim.entities.robot import Robot

from embodichain_functors._common import ParamError, validated
from embodichain_functors._functor import CheckedFunctor

__all__ = ["joint_velocity_penalty", "joint_limit_penalty", "action_smoothness_penalty"]


def _robot(env: Any, robot_uid: Optional[str]) -> Robot:
    return env.robot if robot_uid is None else env.scene[robot_uid]


def robot_checker(functor: str) -> Any:
    """A param check of ``robot_uid`` (a robot of the scene) and ``part_name`` (one of its control parts)."""

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


@validated(robot_checker("joint_velocity_penalty"), lead=3)
def joint_velocity_penalty(
    env: Any,
    obs: Any,
    action: Any,
    info: dict,
    robot_uid: Optional[str] = None,
    joint_ids: Optional[Sequence[int]] = None,
    part_name: Optional[str] = None,
) -> torch.Tensor:
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


@validated(robot_checker("joint_limit_penalty"), lead=3)
def joint_limit_penalty(
    env: Any,
    obs: Any,
    action: Any,
    info: dict,
    robot_uid: Optional[str] = None,
    joint_ids: Any = None,
    margin: float = 0.1,
) -> torch.Tensor:
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


def _flat(action: Any) -> Optional[torch.Tensor]:
    """A (N, k) float tensor of an action (tensor or dict of tensors; flags are skipped)."""
    if isinstance(action, dict):
        parts = [
            torch.as_tensor(action[k]).float().flatten(1)
            for k in sorted(action)
            if torch.as_tensor(action[k]).dtype != torch.bool
        ]
        return torch.cat(parts, -1) if parts else None
    return None if action is None else torch.as_tensor(action).float().flatten(1)


class action_smoothness_penalty(CheckedFunctor):
    """``-||a_t - a_{t-1}||`` of the (processed) action; 0 on the first step of an episode.

    The previous action is kept per env and cleared when the env resets. Dict
    actions (several terms) are compared on their concatenated tensors.

    Example:
        ``{"func": "action_smoothness_penalty", "weight": 0.01}``
    """

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._prev: Optional[torch.Tensor] = None
        self._valid = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        """Forget the previous action of ``env_ids`` (all when ``None``)."""
        self._valid[slice(None) if env_ids is None else torch.as_tensor(env_ids).long()] = False

    def __call__(self, env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
        current = _flat(action)
        if current is None or current.shape[0] != env.num_envs:
            return torch.zeros(env.num_envs, device=env.device)
        if self._prev is None or self._prev.shape != current.shape:
            self._prev, self._valid = current.clone(), torch.zeros_like(self._valid)
        zero = torch.zeros(env.num_envs, device=current.device)
        out = torch.where(self._valid, -(current - self._prev).norm(dim=-1), zero)
        self._prev, self._valid = current.clone(), torch.ones_like(self._valid)
        return out
