"""Robot observations: joint data normalized to the limits (a ``modify`` functor
``f(env, data, **params) -> new data``) and the end-effector pose by forward kinematics."""

from __future__ import annotations

import builtins
from typing import Any, Optional, Sequence

import torch

from embodichain_functors._common import ParamError, as_range, validated
from embodichain_functors._kinematics import check_ik, check_part, default_part, eef_pose

__all__ = ["normalize_robot_joint_data", "get_robot_eef_pose"]


def _check_normalize(
    env: Any, joint_ids: Optional[Sequence[int]] = None, limit: str = "qpos_limits", range: Sequence[float] = (0.0, 1.0)
) -> None:
    name = "normalize_robot_joint_data"
    if limit not in ("qpos_limits", "qvel_limits"):
        raise ParamError(name, "limit", f"must be 'qpos_limits' or 'qvel_limits', got {limit!r}")
    as_range(range, name, "range")
    n = len(env.active_joint_ids)
    if joint_ids is not None and any(not 0 <= int(j) < n for j in joint_ids):
        raise ParamError(name, "joint_ids", f"indices into the {n} active joints, got {list(joint_ids)}")


@validated(_check_normalize)
def normalize_robot_joint_data(
    env: Any,
    data: torch.Tensor,
    joint_ids: Optional[Sequence[int]] = None,
    limit: str = "qpos_limits",
    range: Sequence[float] = (0.0, 1.0),
) -> torch.Tensor:
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
def get_robot_eef_pose(
    env: Any, obs: Any, part_name: Optional[str] = None, position_only: bool = False
) -> torch.Tensor:
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
