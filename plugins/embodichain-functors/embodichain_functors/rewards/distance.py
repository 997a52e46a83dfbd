"""Distance and alignment rewards ``f(env, obs, action, info, **params) -> (N,)``, and the
entity position helpers they share (robots with ``control_parts`` use their end effector)."""

from __future__ import annotations

from typing import Any, Optional

import torch

from embodichain_core.sim.entities.robot import Robot
from embodichain_core.utils.math import quat_to_matrix
from embodichain_core.managers.cfg import SceneEntityCfg

from embodichain_functors._common import ParamError, check_positive, validated
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._kinematics import check_ik, default_part, eef_pose
from embodichain_functors.rewards.penalty import robot_checker

__all__ = [
    "distance_between_objects",
    "distance_to_target",
    "incremental_distance_to_target",
    "reaching_behind_object",
    "orientation_alignment",
    "position_of",
    "rotation_of",
    "target_positions",
]


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
        raise KeyError(
            f"{functor}: env.{key} does not exist yet; set it (e.g. with randomize_target_pose, "
            f"store_key={key!r}) before rewards are computed"
        )
    target = torch.as_tensor(target, dtype=torch.float32)
    return target[:, :3, 3] if target.dim() == 3 else target[:, :3]


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
    return torch.exp(-(d**2) / (2.0 * sigma**2)) if exponential else -d


@validated(_check_entities("distance_between_objects", "source_entity_cfg", "target_entity_cfg"), lead=3)
def distance_between_objects(
    env: Any,
    obs: Any,
    action: Any,
    info: dict,
    source_entity_cfg: Any,
    target_entity_cfg: Any,
    exponential: bool = False,
    sigma: float = 1.0,
) -> torch.Tensor:
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
def distance_to_target(
    env: Any,
    obs: Any,
    action: Any,
    info: dict,
    source_entity_cfg: Any,
    target_pose_key: str = "goal_pose",
    exponential: bool = False,
    sigma: float = 1.0,
    use_xy_only: bool = False,
) -> torch.Tensor:
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

    reads_env_key = "target_pose_key"  # the param naming the env attribute it reads

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

    def __call__(
        self,
        env: Any,
        obs: Any,
        action: Any,
        info: dict,
        source_entity_cfg: Any,
        target_pose_key: str = "goal_pose",
        tanh_scale: float = 10.0,
        positive_weight: float = 1.0,
        negative_weight: float = 1.0,
        use_xy_only: bool = False,
    ) -> torch.Tensor:
        delta = position_of(env, source_entity_cfg) - target_positions(env, target_pose_key, type(self).__name__)
        d = (delta[:, :2] if use_xy_only else delta).norm(dim=-1)
        gain = torch.tanh(tanh_scale * (self._prev - d))
        out = torch.where(gain > 0, positive_weight * gain, negative_weight * gain)
        out = torch.where(self._valid, out, torch.zeros_like(out))
        self._prev, self._valid = d.clone(), torch.ones_like(self._valid)
        return out


@validated(_check_entities("orientation_alignment", "source_entity_cfg", "target_entity_cfg"), lead=3)
def orientation_alignment(
    env: Any, obs: Any, action: Any, info: dict, source_entity_cfg: Any, target_entity_cfg: Any
) -> torch.Tensor:
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


def _check_behind(
    env: Any, object_cfg: Any, part_name: Optional[str] = None, distance_scale: float = 5.0, **_: Any
) -> None:
    if getattr(object_cfg, "uid", None) not in env.scene:
        raise ParamError("reaching_behind_object", "object_cfg", f"no entity {object_cfg!r} in the scene")
    check_positive(distance_scale, "reaching_behind_object", "distance_scale")
    robot_checker("reaching_behind_object")(env, part_name=part_name)
    check_ik(env.robot, default_part(env, env.robot, part_name), "reaching_behind_object", "part_name")


@validated(_check_behind, lead=3)
def reaching_behind_object(
    env: Any,
    obs: Any,
    action: Any,
    info: dict,
    object_cfg: SceneEntityCfg,
    target_pose_key: str = "goal_pose",
    behind_offset: float = 0.015,
    height_offset: float = 0.015,
    distance_scale: float = 5.0,
    part_name: Optional[str] = None,
) -> torch.Tensor:
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


distance_to_target.reads_env_key = "target_pose_key"  # type: ignore[attr-defined]
reaching_behind_object.reads_env_key = "target_pose_key"  # type: ignore[attr-defined]
