"""``wait_for_dynamic_objects_to_settle``: simulate the selected envs until objects rest."""

from __future__ import annotations

import warnings
from typing import Any, Optional, Sequence

import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.entities.robot import Robot
from embodichain_core.managers.cfg import SceneEntityCfg

from embodichain_functors._common import ParamError, check_positive, env_ids_of, validated
from embodichain_functors._sim import step_envs

__all__ = ["wait_for_dynamic_objects_to_settle"]

_NAME = "wait_for_dynamic_objects_to_settle"


def _targets(env: Any, entity_cfgs: Optional[Sequence[Any]]) -> list[tuple[Any, Any]]:
    """``(entity, body selection)`` pairs: the given ones, or every dynamic non-robot entity."""
    scene = env.scene
    if entity_cfgs is None:
        out = [(o, None) for o in scene.rigid_objects.values() if o.is_dynamic]
        out += [(g, None) for g in scene.groups.values() if g.members and g.members[0].is_dynamic]
        return out + [(a, None) for a in scene.articulations.values()]
    out = []
    for cfg in entity_cfgs:
        uid = cfg["uid"] if isinstance(cfg, dict) else cfg.uid
        out.append((scene.get(uid), getattr(cfg, "body_ids", None)))
    return out


def _speeds(env: Any, entity: Any, bodies: Any) -> tuple[torch.Tensor, torch.Tensor]:
    """(N,) largest linear and angular speeds of an entity's bodies."""
    if isinstance(entity, RigidObjectGroup):
        vel = entity.get_velocity()  # (N, K, 6)
    elif isinstance(entity, RigidObject):
        vel = entity.get_velocity()[:, None]
    else:
        links = entity.body_ids if bodies is None or isinstance(bodies, slice) else entity.body_ids[list(bodies)]
        cvel = env.sim.cvel[:, links.long()]  # com-based [angular, linear]
        vel = torch.cat((cvel[..., 3:], cvel[..., :3]), -1).float()
    lin, ang = vel[..., :3].norm(dim=-1).amax(-1), vel[..., 3:].norm(dim=-1).amax(-1)
    bad = ~torch.isfinite(vel).all(-1).all(-1)
    return lin.masked_fill(bad, float("inf")), ang.masked_fill(bad, float("inf"))


def _check(
    env: Any,
    entity_cfgs: Any = None,
    linear_velocity_threshold: Any = 0.03,
    angular_velocity_threshold: Any = 0.2,
    min_steps: Any = 10,
    max_steps: Any = 240,
    check_interval_steps: Any = 2,
    required_stable_checks: Any = 3,
    timeout_behavior: Any = "warn",
    allow_partial_envs: Any = True,
) -> None:
    for key, value in (
        ("linear_velocity_threshold", linear_velocity_threshold),
        ("angular_velocity_threshold", angular_velocity_threshold),
    ):
        check_positive(value, _NAME, key)
    counts = (
        ("min_steps", min_steps),
        ("max_steps", max_steps),
        ("check_interval_steps", check_interval_steps),
        ("required_stable_checks", required_stable_checks),
    )
    for key, value in counts:
        if isinstance(value, bool) or not isinstance(value, int) or value < (0 if key == "min_steps" else 1):
            raise ParamError(_NAME, key, f"must be an int >= {0 if key == 'min_steps' else 1}, got {value!r}")
    if min_steps > max_steps:
        raise ParamError(_NAME, "min_steps", f"min_steps {min_steps} is above max_steps {max_steps}")
    if timeout_behavior not in ("warn", "raise"):
        raise ParamError(_NAME, "timeout_behavior", f"must be 'warn' or 'raise', got {timeout_behavior!r}")
    for entity, _ in _targets(env, entity_cfgs):
        movable = isinstance(entity, (RigidObject, RigidObjectGroup, Articulation)) and not isinstance(entity, Robot)
        if not movable:
            raise ParamError(_NAME, "entity_cfgs", f"{entity!r} is not a dynamic object, group or articulation")
        if isinstance(entity, RigidObject) and not entity.is_dynamic:
            raise ParamError(_NAME, "entity_cfgs", f"{entity.uid!r} is {entity.cfg.body_type}; it never moves")


@validated(_check)
def wait_for_dynamic_objects_to_settle(
    env: Any,
    env_ids: Any,
    entity_cfgs: Optional[Sequence[SceneEntityCfg]] = None,
    linear_velocity_threshold: float = 0.03,
    angular_velocity_threshold: float = 0.2,
    min_steps: int = 10,
    max_steps: int = 240,
    check_interval_steps: int = 2,
    required_stable_checks: int = 3,
    timeout_behavior: str = "warn",
    allow_partial_envs: bool = True,
) -> None:
    """Simulate ``env_ids`` (only them) until every dynamic object rests.

    An env has settled once all its bodies stay below both speed thresholds for
    ``required_stable_checks`` consecutive checks (one every
    ``check_interval_steps`` physics steps, from ``min_steps`` on); settled envs
    stop stepping. NaN counts as moving. Other envs are never stepped, so partial
    selections (auto-resets of some envs) are safe.

    Args:
        env: the env.
        env_ids: envs to settle.
        entity_cfgs: entities to watch (``body_names`` limit an articulation's links);
            default: dynamic rigid objects, dynamic groups and non-robot articulations.
        linear_velocity_threshold: m/s.
        angular_velocity_threshold: rad/s.
        min_steps: physics steps before the first check.
        max_steps: give up after this many steps.
        check_interval_steps: physics steps between checks.
        required_stable_checks: consecutive calm checks needed.
        timeout_behavior: ``"warn"`` (with the speeds of the unsettled envs) or ``"raise"``.
        allow_partial_envs: ``False`` rejects calls for a subset of the envs.

    Example:
        ``{"func": "wait_for_dynamic_objects_to_settle", "mode": "reset", "params": {"max_steps": 200}}``
    """
    ids = env_ids_of(env, env_ids)
    if not allow_partial_envs and len(ids) != env.num_envs:
        raise ValueError(f"{_NAME}: called for {len(ids)} of {env.num_envs} envs; set allow_partial_envs=True")
    targets, active = _targets(env, entity_cfgs), ids.clone()
    calm, steps = torch.zeros(env.num_envs, dtype=torch.long), 0
    while steps < max_steps and len(active):
        step_envs(env, active, check_interval_steps)
        steps += check_interval_steps
        if steps < min_steps:
            continue
        still = torch.ones(env.num_envs, dtype=torch.bool)
        for entity, bodies in targets:
            lin, ang = _speeds(env, entity, bodies)
            still &= (lin < linear_velocity_threshold) & (ang < angular_velocity_threshold)
        calm = torch.where(still, calm + 1, torch.zeros_like(calm))
        active = active[calm[active] < required_stable_checks]
    if len(active):
        speeds = [tuple(round(float(v[active].max()), 4) for v in _speeds(env, e, b)) for e, b in targets]
        message = (
            f"{_NAME}: envs {active.tolist()} still moving after {steps} steps (max lin/ang speed per entity: {speeds})"
        )
        if timeout_behavior == "raise":
            raise RuntimeError(message)
        warnings.warn(message, RuntimeWarning, stacklevel=2)
