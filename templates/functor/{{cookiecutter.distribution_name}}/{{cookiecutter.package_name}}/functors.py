"""The {{ cookiecutter.kind }} functor ``{{ cookiecutter.functor_name }}``.

The manager passes the env (and, for this kind, {{ {'observation': 'the observation dict', 'reward': 'the observation, the action and the info dict', 'event': 'the ids of the envs concerned', 'randomization': 'the ids of the envs concerned'}[cookiecutter.kind] }})
first; the rest of the signature is filled from the ``params`` of the functor's config,
which are checked against it when the env is built.
"""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.managers import SceneEntityCfg
{% if cookiecutter.kind == "observation" %}

def {{ cookiecutter.functor_name }}(env: Any, obs: dict, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    """{{ cookiecutter.description }}: ``(num_envs, 3)``, in the env frame.

    Use it with ``ObservationCfg(func="{{ cookiecutter.functor_name }}", mode="add", name="object/pos",
    params={"entity_cfg": SceneEntityCfg(uid="cube")})``.

    Args:
        env: the env.
        obs: the observation built so far.
        entity_cfg: the object (a rigid object or an articulation).
    """
    return env.scene[entity_cfg.uid].get_local_pose()[:, :3].float()
{% elif cookiecutter.kind == "reward" %}

def {{ cookiecutter.functor_name }}(env: Any, obs: dict, action: Any, info: dict, entity_cfg: SceneEntityCfg,
        target: tuple[float, float, float] = (0.0, 0.0, 0.1)) -> torch.Tensor:
    """{{ cookiecutter.description }}: ``(num_envs,)``, higher is better.

    Use it with ``RewardCfg(func="{{ cookiecutter.functor_name }}", weight=1.0,
    params={"entity_cfg": SceneEntityCfg(uid="cube"), "target": (0.5, 0.0, 0.1)})``.

    Args:
        env: the env.
        obs: the observation of this step.
        action: the action of this step.
        info: the info dict of this step (``success``, ``fail``, ``metrics``, ...).
        entity_cfg: the object.
        target: the target point in the env frame.
    """
    position = env.scene[entity_cfg.uid].get_local_pose()[:, :3].float()
    goal = torch.as_tensor(target, dtype=position.dtype, device=position.device)
    return -torch.linalg.norm(position - goal, dim=-1)
{% elif cookiecutter.kind == "event" %}

def {{ cookiecutter.functor_name }}(env: Any, env_ids: torch.Tensor, entity_cfg: SceneEntityCfg,
        offset_range: tuple[float, float] = (-0.05, 0.05)) -> None:
    """{{ cookiecutter.description }}: along x, uniformly in ``offset_range`` (metres).

    Use it with ``EventCfg(func="{{ cookiecutter.functor_name }}", mode="reset",
    params={"entity_cfg": SceneEntityCfg(uid="cube"), "offset_range": (-0.05, 0.05)})``.

    Args:
        env: the env.
        env_ids: the envs concerned (all of them at startup, the reset ones on reset).
        entity_cfg: the object to move.
        offset_range: ``(low, high)`` of the offset.
    """
    obj = env.scene[entity_cfg.uid]
    pose = obj.get_local_pose()[env_ids]
    low, high = offset_range
    # one draw per env, from that env's per-episode stream (reproducible, independent of other envs)
    pose[:, 0] += torch.from_numpy(env.rng.uniform(env_ids, low, high)).to(pose.dtype)
    obj.set_local_pose(pose, env_ids)
{% elif cookiecutter.kind == "randomization" %}

def {{ cookiecutter.functor_name }}(env: Any, env_ids: torch.Tensor, entity_cfg: SceneEntityCfg,
        mass_range: tuple[float, float] = (0.05, 0.5)) -> None:
    """{{ cookiecutter.description }}: uniformly in ``mass_range`` (kg), per env.

    Use it with ``EventCfg(func="{{ cookiecutter.functor_name }}", mode="reset",
    params={"entity_cfg": SceneEntityCfg(uid="cube"), "mass_range": (0.05, 0.5)})``.

    Args:
        env: the env.
        env_ids: the envs concerned (all of them at startup, the reset ones on reset).
        entity_cfg: a dynamic rigid object.
        mass_range: ``(low, high)`` of the mass.
    """
    low, high = mass_range
    mass = torch.from_numpy(env.rng.uniform(env_ids, low, high))  # one draw per env, float64
    env.scene[entity_cfg.uid].set_mass(mass, env_ids)
{% endif -%}
