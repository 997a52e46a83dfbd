"""Joint randomization: passive damping and stiffness, and drive gains, per env and joint.

Values are drawn from each env's episode stream ``env.rng`` and written into the per-env
model fields of ``env_ids`` only (``dof_damping``, ``jnt_stiffness``, the drive actuators' gains).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.articulation import Articulation

from embodichain_functors._common import ParamError, as_range, entity_of, env_ids_of, uniform, uniform_np, validated
from embodichain_functors._entities import joint_ids_of, mj_joint_ids
from embodichain_functors._sim import write_model

__all__ = ["randomize_joint_damping", "randomize_joint_stiffness", "randomize_joint_drive"]


def _joint_param(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, value_range: Any, relative: bool, field: str, name: str
) -> None:
    """Draw one value per env and joint into ``field`` (``dof_damping`` or ``jnt_stiffness``)."""
    ids = env_ids_of(env, env_ids)
    art = env.scene[entity_cfg.uid]
    joints = joint_ids_of(art, entity_cfg)
    index = art.dof_adr.numpy()[joints] if field == "dof_damping" else mj_joint_ids(art, joints)
    low, high = as_range(value_range, name, f"{field.split('_')[1]}_range")
    sample = uniform_np(env, ids, low, high, (len(index),))
    base = getattr(env.scene.model, field)[index][None, :] if relative else 0.0
    if field == "dof_damping":  # the entity's public per-env setter
        art.set_joint_damping(np.maximum(base + sample, 0.0), joint_ids=joints, env_ids=ids)
        return
    write_model(env.sim, ids, [(field, index, np.maximum(base + sample, 0.0))])


def _check_joint(name: str, param: str) -> Any:
    def check(env: Any, entity_cfg: SceneEntityCfg, relative: bool = False, **params: Any) -> None:
        entity_of(env, entity_cfg, name, (Articulation,))
        low, _ = as_range(params[param], name, param)
        if not relative and (low < 0).any():
            raise ParamError(name, param, f"values must be >= 0, got {params[param]!r}")

    return check


@validated(_check_joint("randomize_joint_damping", "damping_range"))
def randomize_joint_damping(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, damping_range: Any, relative: bool = False
) -> None:
    """Draw passive joint damping (MuJoCo ``dof_damping``) per env and joint.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the articulation; ``joint_names`` selects joints (all by default).
        damping_range: ``[low, high]`` in N*m*s/rad (or N*s/m).
        relative: add the draw to the configured damping (clamped at 0).

    Example:
        ``{"func": "randomize_joint_damping", "mode": "reset", "params": {"entity_cfg":
        {"uid": "drawer", "joint_names": ["slide_rails"]}, "damping_range": [0.5, 5.0]}}``
    """
    _joint_param(env, env_ids, entity_cfg, damping_range, relative, "dof_damping", "randomize_joint_damping")


@validated(_check_joint("randomize_joint_stiffness", "stiffness_range"))
def randomize_joint_stiffness(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, stiffness_range: Any, relative: bool = False
) -> None:
    """Draw passive joint spring stiffness (MuJoCo ``jnt_stiffness``) per env and joint.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the articulation; ``joint_names`` selects joints (all by default).
        stiffness_range: ``[low, high]`` in N*m/rad (or N/m); springs pull to the configured pose.
        relative: add the draw to the configured stiffness (clamped at 0).

    Example:
        ``{"func": "randomize_joint_stiffness", "mode": "reset", "params": {"entity_cfg":
        {"uid": "drawer"}, "stiffness_range": [0.0, 20.0]}}``
    """
    _joint_param(env, env_ids, entity_cfg, stiffness_range, relative, "jnt_stiffness", "randomize_joint_stiffness")


_DRIVE_PARAMS = ("stiffness_range", "damping_range", "max_effort_range")


def _check_drive(env: Any, entity_cfg: SceneEntityCfg, relative: bool = False, **ranges: Any) -> None:
    name = "randomize_joint_drive"
    art = entity_of(env, entity_cfg, name, (Articulation,))
    given = {k: v for k, v in ranges.items() if v is not None}
    if not given:
        raise ParamError(name, "stiffness_range", f"give at least one of {list(_DRIVE_PARAMS)}")
    for key, rng in given.items():
        low, _ = as_range(rng, name, key)
        if not relative and (low < 0).any():
            raise ParamError(name, key, f"values must be >= 0, got {rng!r}")
    if not any(int(art.pos_act[j]) >= 0 for j in joint_ids_of(art, entity_cfg)):
        raise ParamError(name, "entity_cfg", f"no selected joint of {entity_cfg.uid!r} has a drive")


def _drive_base(art: Articulation, key: str, joint: int) -> float:
    model = art.scene.model
    if key == "stiffness":
        return float(model.actuator_gainprm[int(art.pos_act[joint]), 0])
    if key == "damping":
        return float(model.actuator_gainprm[int(art.vel_act[joint]), 0])
    return float(model.jnt_actfrcrange[mj_joint_ids(art, [joint])[0], 1])


@validated(_check_drive)
def randomize_joint_drive(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    stiffness_range: Any = None,
    damping_range: Any = None,
    max_effort_range: Any = None,
    relative: bool = False,
) -> None:
    """Draw joint drive gains (PD stiffness, damping) and effort limits per env and joint.

    Only driven joints are changed (``drive_pros.drive_type="force"``).

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the robot or articulation; ``joint_names`` selects joints.
        stiffness_range: ``[low, high]`` of the position gain ``kp`` (``None``: unchanged).
        damping_range: ``[low, high]`` of the velocity gain ``kv`` (``None``: unchanged).
        max_effort_range: ``[low, high]`` of the joint effort limit (``None``: unchanged).
        relative: add the draws to the configured values (clamped at 0).

    Example:
        ``{"func": "randomize_joint_drive", "mode": "reset", "params": {"entity_cfg":
        {"uid": "robot", "joint_names": ["joint[1-7]"]}, "stiffness_range": [800, 1200]}}``
    """
    ids = env_ids_of(env, env_ids)
    art = env.scene[entity_cfg.uid]
    joints = [j for j in joint_ids_of(art, entity_cfg) if int(art.pos_act[j]) >= 0]
    values: dict[str, torch.Tensor] = {}
    for key, rng in zip(("stiffness", "damping", "max_effort"), (stiffness_range, damping_range, max_effort_range)):
        if rng is None:
            continue
        low, high = as_range(rng, "randomize_joint_drive", f"{key}_range")
        draw = uniform(env, ids, low, high, (len(joints),))
        if relative:
            draw = draw + torch.tensor([_drive_base(art, key, j) for j in joints], dtype=torch.float64)
        values[key] = draw.clamp_min(0.0)
    for k, joint in enumerate(joints):
        art.set_joint_drive(**{key: v[:, k] for key, v in values.items()}, joint_ids=[joint], env_ids=ids)
