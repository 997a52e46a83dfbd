"""Construction of an :class:`~embodichain_core.envs.embodied_env.EmbodiedEnv`, by role.

The env is built by :class:`~embodichain_core.envs.base_env.BaseEnv`'s ``__init__``, whose
overrides ``EmbodiedEnv`` implements with these: :func:`resolve_cfg` (config and keyword
overrides) -> :func:`check_cfg` (validation, the manager sections resolved once,
extensions) -> the config's entities (``scene_setup.add_config_entities``) and the compile
-> :func:`resolve_robot` (robot, active joints, their drive targets, the joint-limit action
space) -> :func:`build_managers` (event manager + startup events, observation, reward,
action, dataset managers, the env attributes functors pass between them) -> the action
space, the first observation and the spaces -> :func:`action_checker` (the boundary check
of ``step``). The loop itself (``step``, ``reset``) lives in the env class, top to bottom.
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium as gym
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.config.ignored import warn_ignored
from embodichain_core.config.sections import check_sections
from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.envs.cfg import EnvCfg
from embodichain_core.envs.robot_io import RobotIO
from embodichain_core.envs.scene_setup import filter_functors, resolve_active_joints
from embodichain_core.managers.action_manager import ActionManager
from embodichain_core.managers.dataset_manager import DatasetManager
from embodichain_core.managers.env_keys import check_env_keys
from embodichain_core.managers.event_manager import EventManager
from embodichain_core.managers.observation_manager import ObservationManager
from embodichain_core.managers.reward_manager import RewardManager
from embodichain_core.plugins import task_registry
from embodichain_core.plugins.registry import describe_target
from embodichain_core.utils.suggest import did_you_mean


def task_episode_limit(env_cls: type) -> Optional[int]:
    """The ``max_episode_steps`` the tasks of ``env_cls`` register (``None``: none, or they differ)."""
    target = describe_target(env_cls)
    limits = {e.meta["max_episode_steps"] for e in task_registry().entries() if e.target_repr == target}
    limits.discard(None)
    return limits.pop() if len(limits) == 1 else None


def resolve_cfg(env_cls: Any, cfg: Any, overrides: dict) -> Any:
    """The env's own copy of ``cfg`` (``None``: ``env_cls.cfg_cls()``; a dict: ``from_dict``)
    with the keyword ``overrides`` set; the episode limit registered with the task of
    ``env_cls`` (the tasks hook, or ``register_env``) replaces ``max_episode_steps`` when the
    config leaves it at its class default.

    Raises:
        ConfigError: an override names no config field.
    """
    cfg_cls = env_cls.cfg_cls
    registered_limit = task_episode_limit(env_cls)
    if cfg is None:
        cfg = cfg_cls()
    elif isinstance(cfg, dict):
        cfg = cfg_cls.from_dict(cfg)
    else:
        cfg = cfg.copy()
    if registered_limit is not None and cfg.max_episode_steps == EnvCfg().max_episode_steps:
        cfg.max_episode_steps = int(registered_limit)
    names = set(cfg.__dataclass_fields__)
    for key, value in overrides.items():
        if key not in names:
            raise ConfigError(key, f"unknown env argument {key!r}.{did_you_mean(key, names)}")
        setattr(cfg, key, value)
    return cfg


def bind_extensions(env: Any) -> None:
    """Set ``cfg.extensions`` as env attributes (one that would hide a class attribute is an error)."""
    for key, value in (env.cfg.extensions or {}).items():
        if hasattr(type(env), key):
            raise ConfigError(
                f"env.extensions.{key}", f"{key!r} would shadow the env attribute of the same name; rename it"
            )
        setattr(env, key, value)


def check_cfg(env: Any) -> dict:
    """Validate the config (memory estimate included), check the manager sections (each
    functor resolved once, for the build), warn about ignored settings, bind extensions.

    Returns:
        The checked manager sections after the filters (``filter_visual_rand``,
        ``filter_dataset_saving``), for :func:`build_managers`.

    Raises:
        ConfigError: the first bad value, at its config path, before anything is built.
    """
    env.cfg.validate(functors=False)
    functors = filter_functors(env.cfg, check_sections(env.cfg, warn=True))
    warn_ignored(env.cfg)
    bind_extensions(env)
    return functors


def resolve_robot(env: Any) -> gym.spaces.Box:
    """The robot (the scene's first), the sensors, the active joints and their addresses and
    drive targets (``env._robot_io``), once the scene is built.

    Returns:
        The default action space: a ``Box`` of the active joints' position limits.
    """
    env.robot = next(iter(env.scene.robots.values()))
    env.sensors = env.scene.sensors
    env.active_joint_ids = resolve_active_joints(env.cfg, env.robot)
    aid = torch.as_tensor(env.active_joint_ids, dtype=torch.long)
    # addresses, drive targets and fast paths of the active joints, resolved once
    env._robot_io = RobotIO(env.sim, env.robot, env.active_joint_ids, env.num_envs)
    limits = env.robot.get_qpos_limits()[0, aid].cpu().numpy()  # the sim device may be a GPU
    return gym.spaces.Box(low=limits[:, 0], high=limits[:, 1], dtype=np.float32)


def build_managers(env: Any, functors: dict) -> None:
    """Event manager (then the ``startup`` events), observation, reward, action and
    dataset managers from the checked sections ``functors`` (:func:`check_cfg`)."""
    env.event_manager = EventManager(functors["events"], env)
    env.event_manager.apply("startup", None)
    env.observation_manager = ObservationManager(functors["observations"], env)
    env.reward_manager = RewardManager(functors["rewards"], env)
    env.action_manager = ActionManager(functors["actions"], env)
    if functors["dataset"] is not None:
        manager = DatasetManager(functors["dataset"], env)
        env.dataset_manager = manager if len(manager) else None
    # functors passing an env attribute (randomize_target_pose -> target_position) agree on its name
    env._pending_env_keys = check_env_keys(env)


def recorders_need_buffer(manager: Optional[DatasetManager]) -> bool:
    """A recorder that reads ``env.rollout_buffer`` sets ``uses_rollout_buffer = True``."""
    return manager is not None and any(getattr(e.func, "uses_rollout_buffer", False) for e in manager.entries.values())


def action_checker(env: Any) -> ActionChecker:
    """The boundary check of ``step`` (see :mod:`embodichain_core.envs.action_check`).

    Action terms take their own width (a dict by term name or input key); without
    terms, joint commands take the active joints' or all joints' width (a dict by
    ``qpos``/``qvel``/``qf``).
    """
    manager = env.action_manager
    terms = manager.terms("pre") if manager is not None else {}
    if terms:
        keys: dict[str, list[int]] = {}
        for name, term in terms.items():
            keys[name] = keys[term.input_key] = [term.action_dim]
        dims = [t.action_dim for t in terms.values()]
        detail = f"the action terms {list(terms)} take {dims} values in this order (total {sum(dims)})"
        return ActionChecker(
            env.num_envs, [sum(dims)], env.device, env.action_space, keys, detail, strict=env.cfg.strict_actions
        )
    n_active = len(env.active_joint_ids)
    widths = sorted({n_active, env.robot.dof}, key=lambda w: w != n_active)
    dict_widths = {key: widths for key in ("qpos", "qvel", "qf")}
    return ActionChecker(env.num_envs, widths, env.device, env.action_space, dict_widths, strict=env.cfg.strict_actions)
