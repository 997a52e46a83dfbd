"""Stateful reward functors (state cleared per env on reset) and the pose helpers of
:mod:`embodichain_functors.rewards` (import the functors from there)."""

from __future__ import annotations

from typing import Any, Optional

import torch

from embodichain_core.sim.entities.robot import Robot
from embodichain_core.utils.math import quat_to_matrix

from embodichain_functors._common import ParamError, check_positive
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._kinematics import eef_pose

__all__ = ["incremental_distance_to_target", "action_smoothness_penalty", "position_of", "rotation_of",
           "target_positions"]


def _pose_matrix(env: Any, entity_cfg: Any) -> torch.Tensor:
    """(N, 4, 4) pose of an entity; a robot with ``control_parts`` gives that part's end effector."""
    entity = env.scene[entity_cfg.uid]
    parts = getattr(entity_cfg, "control_parts", None)
    if isinstance(entity, Robot) and parts:
        return eef_pose(entity, parts if isinstance(parts, str) else parts[0])
    if hasattr(entity, "get_arena_pose"):
        return entity.get_arena_pose(to_matrix=True)
    return entity.get_local_pose(to_matrix=True)


def position_of(env: Any, entity_cfg: Any) -> torch.Tensor:
    """(N, 3) position of an entity in the env frame."""
    entity = env.scene[entity_cfg.uid]
    if isinstance(entity, Robot) or hasattr(entity, "get_arena_pose"):
        return _pose_matrix(env, entity_cfg)[:, :3, 3].float()
    return entity.get_local_pose()[:, :3].float()


def rotation_of(env: Any, entity_cfg: Any) -> torch.Tensor:
    """(N, 3, 3) orientation of an entity in the env frame."""
    entity = env.scene[entity_cfg.uid]
    if isinstance(entity, Robot) or hasattr(entity, "get_arena_pose"):
        return _pose_matrix(env, entity_cfg)[:, :3, :3].float()
    return quat_to_matrix(entity.get_local_pose()[:, 3:7]).float()


def target_positions(env: Any, key: str, functor: str) -> torch.Tensor:
    """(N, 3) positions of ``env.<key>`` ((N, 3), (N, 7) or (N, 4, 4)); a missing key raises."""
    target = getattr(env, key, None)
    if target is None:
        raise KeyError(f"{functor}: env.{key} does not exist yet; set it (e.g. with randomize_target_pose, "
                       f"store_key={key!r}) before rewards are computed")
    target = torch.as_tensor(target, dtype=torch.float32)
    return target[:, :3, 3] if target.dim() == 3 else target[:, :3]


class incremental_distance_to_target(CheckedFunctor):
    """``tanh(s * (d_prev - d))``: positive when an entity gets closer to its target.

    Progress is weighted by ``positive_weight`` and regress by ``negative_weight``.
    The previous distance is kept per env and cleared when the env resets, so the
    first step of every episode gives 0.

    Args (params):
        source_entity_cfg: the entity.
        target_pose_key: env attribute with the targets (a missing one raises).
        tanh_scale: ``s`` (1/metres).
        positive_weight: weight of progress.
        negative_weight: weight of regress.
        use_xy_only: ignore z.

    Example:
        ``{"func": "incremental_distance_to_target", "weight": 1.0, "params": {"source_entity_cfg":
        {"uid": "cube"}, "target_pose_key": "goal_pose", "tanh_scale": 10.0}}``
    """

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._prev = torch.zeros(env.num_envs)
        self._valid = torch.zeros(env.num_envs, dtype=torch.bool)

    def check(self, env: Any, source_entity_cfg: Any = None, tanh_scale: Any = 10.0, **_: Any) -> None:
        if getattr(source_entity_cfg, "uid", None) not in env.scene:
            raise ParamError(type(self).__name__, "source_entity_cfg", f"no entity {source_entity_cfg!r} in the scene")
        check_positive(tanh_scale, type(self).__name__, "tanh_scale")

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        """Forget the previous distance of ``env_ids`` (all when ``None``)."""
        self._valid[slice(None) if env_ids is None else torch.as_tensor(env_ids).long()] = False

    def __call__(self, env: Any, obs: Any, action: Any, info: dict, source_entity_cfg: Any,
                 target_pose_key: str = "target_pose", tanh_scale: float = 10.0, positive_weight: float = 1.0,
                 negative_weight: float = 1.0, use_xy_only: bool = False) -> torch.Tensor:
        delta = position_of(env, source_entity_cfg) - target_positions(env, target_pose_key, type(self).__name__)
        d = (delta[:, :2] if use_xy_only else delta).norm(dim=-1)
        gain = torch.tanh(tanh_scale * (self._prev - d))
        out = torch.where(gain > 0, positive_weight * gain, negative_weight * gain)
        out = torch.where(self._valid, out, torch.zeros_like(out))
        self._prev, self._valid = d.clone(), torch.ones_like(self._valid)
        return out


def _flat(action: Any) -> Optional[torch.Tensor]:
    """A (N, k) float tensor of an action (tensor or dict of tensors; flags are skipped)."""
    if isinstance(action, dict):
        parts = [torch.as_tensor(action[k]).float().flatten(1) for k in sorted(action)
                 if torch.as_tensor(action[k]).dtype != torch.bool]
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
        self._valid = torch.zeros(env.num_envs, dtype=torch.bool)

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        """Forget the previous action of ``env_ids`` (all when ``None``)."""
        self._valid[slice(None) if env_ids is None else torch.as_tensor(env_ids).long()] = False

    def __call__(self, env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
        current = _flat(action)
        if current is None or current.shape[0] != env.num_envs:
            return torch.zeros(env.num_envs)
        if self._prev is None or self._prev.shape != current.shape:
            self._prev, self._valid = current.clone(), torch.zeros_like(self._valid)
        out = torch.where(self._valid, -(current - self._prev).norm(dim=-1), torch.zeros(env.num_envs))
        self._prev, self._valid = current.clone(), torch.ones_like(self._valid)
        return out
