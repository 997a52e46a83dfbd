"""The functors of {{ cookiecutter.task_id }}: a reset event, an observation and a reward.

Every functor gets the env first; the rest of its signature comes from the ``params`` of
its config (checked when the env is built). The configs refer to them as
``"{{ cookiecutter.package_name }}.functors:<name>"`` strings, or pass the functions.
"""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.managers import SceneEntityCfg


def shift_object(env: Any, env_ids: torch.Tensor, entity_cfg: SceneEntityCfg,
                 offset_range: tuple[float, float] = (-0.05, 0.05)) -> None:
    """Reset event: move the object along x and y by a random offset in ``offset_range``.

    Args:
        env: the env.
        env_ids: the envs being reset.
        entity_cfg: the object to move.
        offset_range: ``(low, high)`` of the offset, in metres.
    """
    obj = env.scene[entity_cfg.uid]
    pose = obj.get_local_pose()[env_ids]
    low, high = offset_range
    # one (x, y) draw per env, from that env's per-episode stream
    pose[:, :2] += torch.from_numpy(env.rng.uniform(env_ids, low, high, shape=(2,))).to(pose.dtype)
    obj.set_local_pose(pose, env_ids)


def object_position(env: Any, obs: dict, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    """Observation: the object's position in the env frame, shape ``(num_envs, 3)``."""
    return env.scene[entity_cfg.uid].get_local_pose()[:, :3].float()


def reach_distance(env: Any, obs: dict, action: Any, info: dict, entity_cfg: SceneEntityCfg,
                   link_name: str = "ee") -> torch.Tensor:
    """Reward term: minus the distance from the robot link ``link_name`` to the object."""
    link = env.robot.get_link_pose(link_name)[:, :3]
    target = env.scene[entity_cfg.uid].get_local_pose()[:, :3]
    return -torch.linalg.norm(link - target, dim=-1).float()
