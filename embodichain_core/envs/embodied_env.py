"""``EmbodiedEnv``: builds the scene from ``EmbodiedEnvCfg`` and wires the managers.

Construction: bind ``extensions`` -> scene (robot, lights, background,
articulations, rigid objects, groups, sensors) -> event manager (+ startup
events) -> observation, reward, action, dataset managers -> spaces from the first
observation -> summary.
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium as gym
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.envs.base_env import BaseEnv
from embodichain_core.envs.cfg import EmbodiedEnvCfg
from embodichain_core.envs.episode_rng import episode_seeds_option
from embodichain_core.envs.rollout_buffer import RolloutBuffer
from embodichain_core.envs.scene_setup import build_scene, filter_functors, resolve_active_joints
from embodichain_core.envs.summary import print_summary
from embodichain_core.managers.action_manager import ActionManager
from embodichain_core.managers.dataset_manager import DatasetManager
from embodichain_core.managers.event_manager import EventManager
from embodichain_core.managers.observation_manager import ObservationManager
from embodichain_core.managers.reward_manager import RewardManager


class EmbodiedEnv(BaseEnv):
    """The configuration-driven env (see docs/embodied_env.md).

    Example:
        >>> env = gym.make("MyTask-v0", cfg=MyTaskCfg(num_envs=4))
        >>> obs, info = env.reset(seed=0)
        >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    """

    cfg_cls = EmbodiedEnvCfg

    def __init__(self, cfg: Optional[EmbodiedEnvCfg] = None, num_envs: Optional[int] = None, **kwargs: Any):
        self.event_manager: Optional[EventManager] = None
        self.observation_manager: Optional[ObservationManager] = None
        self.reward_manager: Optional[RewardManager] = None
        self.action_manager: Optional[ActionManager] = None
        self.dataset_manager: Optional[DatasetManager] = None
        self.affordance_datas: dict[str, Any] = {}
        self._detached_uids_for_reset: list[str] = []
        self.rollout_buffer: Optional[RolloutBuffer] = None
        super().__init__(cfg, num_envs, **kwargs)
        if self.cfg.init_rollout_buffer or self._recorders_need_buffer():
            self.cfg.init_rollout_buffer = True
            self.rollout_buffer = RolloutBuffer(self._init_obs, self.single_action_space.shape, self.num_envs,
                                                self.max_episode_steps)
        if self.cfg.verbose:
            print_summary(self)

    # -- construction -----------------------------------------------------------------------
    def _bind_extensions(self) -> None:
        for key, value in (self.cfg.extensions or {}).items():
            if hasattr(type(self), key):
                raise ConfigError(f"env.extensions.{key}",
                                  f"{key!r} would shadow the env attribute of the same name; rename it")
            setattr(self, key, value)

    def _setup_scene(self) -> None:
        self.cfg.validate()
        self._bind_extensions()
        events = filter_functors(self.cfg, "events")
        self.scene = build_scene(self, events)
        self.robot = next(iter(self.scene.robots.values()))
        self.sensors = self.scene.sensors
        self.active_joint_ids = resolve_active_joints(self.cfg, self.robot)
        aid = torch.as_tensor(self.active_joint_ids, dtype=torch.long)
        self._active_qpos_adr = self.robot.qpos_adr[aid]
        self._active_dof_adr = self.robot.dof_adr[aid]
        # per command kind: (driven columns of the action, their actuator ids), resolved once
        self._drive_targets = {
            key: ((acts >= 0), acts[acts >= 0])
            for key, acts in (("qpos", self.robot.pos_act[aid]), ("qvel", self.robot.vel_act[aid]))
        }
        limits = self.robot.get_qpos_limits()[0, aid].numpy()
        self.single_action_space = gym.spaces.Box(low=limits[:, 0], high=limits[:, 1], dtype=np.float32)
        self._events_cfg = events

    def _recorders_need_buffer(self) -> bool:
        """A recorder that reads ``env.rollout_buffer`` sets ``uses_rollout_buffer = True``."""
        manager = self.dataset_manager
        return manager is not None and any(getattr(e.func, "uses_rollout_buffer", False)
                                           for e in manager.entries.values())

    @property
    def sim(self):
        """The batched simulation (``env.sim.qpos`` etc.)."""
        return self.scene.sim

    def _init_sim_state(self) -> None:
        cfg = self.cfg
        self.event_manager = EventManager(self._events_cfg, self)
        self.event_manager.apply("startup", None)
        self.observation_manager = ObservationManager(cfg.observations, self)
        self.reward_manager = RewardManager(cfg.rewards, self)
        self.action_manager = ActionManager(cfg.actions, self)
        space = self.action_manager.single_action_space()
        if space is not None:
            self.single_action_space = space
        dataset = filter_functors(cfg, "dataset")
        if dataset is not None and not cfg.filter_dataset_saving:
            manager = DatasetManager(dataset, self)
            self.dataset_manager = manager if len(manager) else None

    def _action_checker(self) -> ActionChecker:
        """Action terms take their own width (a dict by term name or input key); without
        terms, joint commands take the active joints' or all joints' width (a dict by
        ``qpos``/``qvel``/``qf``)."""
        manager = self.action_manager
        terms = manager.get_terms_by_mode("pre") if manager is not None else {}
        if terms:
            keys: dict[str, list[int]] = {}
            for name, term in terms.items():
                keys[name] = keys[term.input_key] = [term.action_dim]
            dims = [t.action_dim for t in terms.values()]
            detail = f"the action terms {list(terms)} take {dims} values in this order (total {sum(dims)})"
            return ActionChecker(self.num_envs, [sum(dims)], self.device, self.action_space, keys, detail)
        widths = sorted({len(self.active_joint_ids), self.robot.dof}, key=lambda w: w != len(self.active_joint_ids))
        return ActionChecker(self.num_envs, widths, self.device, self.action_space,
                             {key: widths for key in ("qpos", "qvel", "qf")})

    # -- step pieces ----------------------------------------------------------------------------
    def _preprocess_action(self, action: Any) -> Any:
        if self.action_manager is not None and len(self.action_manager):
            return self.action_manager.process_action(action, "pre")
        return action

    def _step_action(self, command: Any) -> None:
        if isinstance(command, dict):
            for key in ("qpos", "qvel", "qf"):
                if key in command:
                    self._apply_command(key, command[key])
            return
        self._apply_command("qpos", command)

    def _apply_command(self, key: str, value: Any) -> None:
        value = torch.as_tensor(value)
        if value.dim() == 1:
            value = value.unsqueeze(0).expand(self.num_envs, -1)
        n_active, dof = len(self.active_joint_ids), self.robot.dof
        if value.shape[-1] == dof and dof != n_active:
            value = value[:, self.active_joint_ids]
        elif value.shape[-1] != n_active:
            raise ValueError(f"{key} command has {value.shape[-1]} values per env; expected {n_active} "
                             f"(active joints) or {dof} (all joints)")
        value = value.to(torch.float64)
        if key == "qf":
            self.sim.qfrc_applied[:, self._active_dof_adr] = value
            return
        columns, actuators = self._drive_targets[key]
        self.sim.ctrl[:, actuators] = value[:, columns]

    def _physics_step(self) -> list[int]:
        return self.sim.step(self.sim_steps_per_control)

    def _update_sim_state(self) -> None:
        self.event_manager.apply("interval")

    def _postprocess_action(self, action: Any) -> Any:
        if self.action_manager is not None and self.action_manager.terms("post"):
            return self.action_manager.process_action(action, "post")
        return action

    def get_obs(self, **kwargs: Any) -> dict:
        sim = self.sim
        dof = self._active_dof_adr
        obs: dict[str, Any] = {"robot": {
            "qpos": sim.qpos[:, self._active_qpos_adr].float(),
            "qvel": sim.qvel[:, dof].float(),
            "qf": (sim.qfrc_actuator[:, dof] + sim.qfrc_applied[:, dof]).float(),
        }}
        if self.sensors:
            obs["sensor"] = {}
            for uid, sensor in self.sensors.items():
                sensor.update()
                obs["sensor"][uid] = sensor.get_data()
        return self.observation_manager.compute(obs) if self.observation_manager else obs

    def _compute_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        reward = self.get_reward(obs, action, info).float()
        if self.reward_manager is not None and len(self.reward_manager):
            reward, terms = self.reward_manager.compute(obs, action, info, reward)
            info["rewards"] = terms
        return reward

    def _after_step(self, obs, action, reward, terminated, truncated, info) -> None:
        if self.rollout_buffer is not None:
            self.rollout_buffer.add(obs, action, reward, terminated, truncated, info["success"])
        if self.dataset_manager is not None:
            self.dataset_manager.record_step(obs, action, reward, terminated, truncated, info)

    # -- reset -------------------------------------------------------------------------------------
    def _reset_envs(self, env_ids: torch.Tensor, options: dict) -> None:
        self._commit_or_discard(env_ids, bool(options.get("save_data", True)))
        # the finished episodes are committed (with their seeds): start the new ones' streams
        self.rng.begin_episodes(env_ids, episode_seeds_option(options, len(env_ids)))
        if self.rollout_buffer is not None:
            self.rollout_buffer.clear(env_ids)
        # whole state rows (also clears a diverged env), detached entities kept as they are
        self.scene.reset_state(env_ids, keep_uids=self._detached_uids_for_reset)
        self.scene.reset(env_ids, excluded_uids=self._detached_uids_for_reset)
        self.event_manager.apply("reset", env_ids)
        for manager in (self.event_manager, self.observation_manager, self.reward_manager, self.action_manager,
                        self.dataset_manager):
            if manager is not None:
                manager.reset(env_ids)

    def _commit_or_discard(self, env_ids: torch.Tensor, save: bool) -> None:
        manager = self.dataset_manager
        if manager is None:
            return
        if not save:
            manager.discard(env_ids)
            return
        if manager.save_failed_episodes:
            keep = torch.ones(len(env_ids), dtype=torch.bool)
        else:
            keep = self._episode_success[env_ids] | self.is_task_success()[env_ids]
        manager.commit(env_ids[keep])
        manager.discard(env_ids[~keep])

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        obs, info = super().reset(seed=seed, options=options)
        ids = (options or {}).get("reset_ids")
        ids = torch.arange(self.num_envs) if ids is None else torch.as_tensor(ids).reshape(-1).long()
        if self.rollout_buffer is not None:
            self.rollout_buffer.set_first_obs(obs, ids)
        if self.dataset_manager is not None:
            self.dataset_manager.record_reset(obs, ids)
        return obs, info

    # -- extras -------------------------------------------------------------------------------------
    def add_detached_uids_for_reset(self, uids: Any) -> None:
        """Exclude entities from the automatic reset to their initial state."""
        self._detached_uids_for_reset += [uids] if isinstance(uids, str) else list(uids)

    def get_sensor(self, name: str) -> Any:
        return self.scene[name]

    @property
    def has_sensors(self) -> bool:
        return bool(self.sensors)

    def set_affordance(self, key: str, value: Any) -> None:
        self.affordance_datas[key] = value

    def get_affordance(self, key: str, default: Any = None) -> Any:
        return self.affordance_datas.get(key, default)

    def close(self) -> None:
        """Finalize recorders (never committing partial episodes) and release sensors; idempotent."""
        if self._closed:
            return
        self._closed = True
        errors = []
        if self.dataset_manager is not None:
            try:
                self.dataset_manager.finalize()
            except Exception as err:
                errors.append(err)
        for sensor in self.sensors.values():
            sensor.close()
        if errors:
            raise errors[0]
