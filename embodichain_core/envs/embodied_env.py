"""``EmbodiedEnv``: the batched, configuration-driven env (leading ``num_envs`` dim everywhere).

Construction (:mod:`embodichain_core.envs.env_build`): config -> timing and seed (shared
with :class:`~embodichain_core.envs.base_env.BaseEnv`) -> scene -> managers -> first
observation and spaces -> action check -> summary.
:meth:`EmbodiedEnv.step` and :meth:`EmbodiedEnv.reset` each read top to bottom, one
named phase after the other; docs/embodied_env.md lists the same phases with the
same numbers. ``step`` auto-resets finished envs in the same call (gymnasium
``AutoresetMode.SAME_STEP``): the terminal observation is in ``info["final_obs"]``
with the mask ``info["_final_obs"]``.
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium as gym
import torch
from gymnasium.vector import AutoresetMode

from embodichain_core.envs import env_build
from embodichain_core.envs.base_env import BaseEnv
from embodichain_core.envs.cfg import EmbodiedEnvCfg
from embodichain_core.envs.episode_rng import episode_seeds_option
from embodichain_core.envs.robot_io import RobotIO
from embodichain_core.envs.rollout_buffer import RolloutBuffer
from embodichain_core.envs.scene_setup import build_scene
from embodichain_core.envs.summary import print_summary
from embodichain_core.envs.task_api import TaskApi
from embodichain_core.managers.env_keys import check_after_first_reset
from embodichain_core.viewing import attach_viewer


class EmbodiedEnv(BaseEnv):
    """The configuration-driven env (see docs/embodied_env.md).

    It builds its scene from the config and runs its own ``step`` and ``reset``: the
    :class:`BaseEnv` overrides of a hand-written step (``design_scene``,
    ``define_action_space``, ``apply_action``, ``step_physics``, ``reset_envs``) are
    not called here, and a subclass defining one is an error.

    Example:
        >>> env = gym.make("MyTask-v0", cfg=MyTaskCfg(num_envs=4))
        >>> obs, info = env.reset(seed=0)
        >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.SAME_STEP}
    cfg_cls: type = EmbodiedEnvCfg
    # set during construction (env_build)
    single_action_space: gym.spaces.Box  # joint-position limits, or the action manager's ``pre`` terms
    scene: Any
    robot: Any
    sensors: dict[str, Any]
    active_joint_ids: list[int]
    event_manager: Any
    observation_manager: Any
    reward_manager: Any
    action_manager: Any
    dataset_manager: Any
    _robot_io: RobotIO
    _check_action: Any  # env_build.action_checker

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        hooks = [name for name in _BASE_ENV_HOOKS if name in cls.__dict__]
        if hooks:
            raise TypeError(
                f"{cls.__name__} defines {', '.join(hooks)}, which only BaseEnv's step calls: EmbodiedEnv "
                "builds its scene from the config and runs its own step (override compute_task_state, "
                "get_reward, check_truncated, get_info or get_obs instead; or subclass BaseEnv)"
            )

    def __init__(
        self,
        cfg: Optional[EmbodiedEnvCfg] = None,
        num_envs: Optional[int] = None,
        render_mode: Optional[str] = None,
        **kwargs: Any,
    ):
        self.event_manager = self.observation_manager = self.reward_manager = None
        self.action_manager = self.dataset_manager = None
        self._pre_terms = self._post_terms = self._obs_terms = self._reward_terms = False  # set once built
        self._pending_env_keys: list = []  # env attributes to find after the first reset (env_keys)
        self.rollout_buffer: Optional[RolloutBuffer] = None
        self._viewer: Optional[Any] = None  # headless: false opens one once built (embodichain_core.viewing)
        # config, timing, device, seed, counters (BaseEnv)
        self._init_run(cfg, num_envs, render_mode, kwargs)
        self._default_reward = type(self).get_reward is TaskApi.get_reward  # zeros: phase 8 skips it
        self._episode_success = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
        # scene, managers, spaces, the action check
        env_build.build_managers(self, env_build.setup_scene(self, build_scene))
        # which manager phases have work (managers are fixed once built): one flag test per step
        self._pre_terms = bool(self.action_manager is not None and len(self.action_manager))
        self._post_terms = bool(self.action_manager is not None and self.action_manager.terms("post"))
        self._obs_terms = bool(self.observation_manager is not None and len(self.observation_manager))
        self._reward_terms = bool(self.reward_manager is not None and len(self.reward_manager))
        self._init_obs = obs = self.get_obs()
        self._init_spaces(obs)
        self._check_action = env_build.action_checker(self)
        if self.cfg.init_rollout_buffer or env_build.recorders_need_buffer(self.dataset_manager):
            self.cfg.init_rollout_buffer = True
            self.rollout_buffer = RolloutBuffer(
                obs, self.single_action_space.shape, self.num_envs, self.max_episode_steps
            )
        if self.cfg.verbose:
            print_summary(self)
        self._viewer = attach_viewer(self)

    # -- the loop ----------------------------------------------------------------------------------
    def step(self, action: Any) -> tuple[dict, torch.Tensor, torch.Tensor, torch.Tensor, dict]:  # type: ignore[override]
        """One control step of every env; ``action`` follows the rule of
        :mod:`embodichain_core.envs.action_check` (a bad action is one clear error)."""
        if self._viewer is not None:  # the viewer's pause / single step / reset / speed
            self._viewer.before_step()
        # 0. action check, once at the boundary
        action = self._check_action(action)
        # 1. action terms (pre): policy action -> command
        command = action
        if self._pre_terms:
            command = self.action_manager.process_action(action, "pre")
        # 2. apply the command: joint targets / efforts into the simulation
        self._apply_command(command)
        # 3. physics: sim_steps_per_control physics steps of every env
        diverged = self.sim.advance(self.sim_steps_per_control)
        # 4. interval events
        self.event_manager.apply("interval")
        # 5. counters: this step counts from here on
        self._elapsed_steps += 1
        # 6. observations
        obs = self.get_obs()
        # 7. task state and info
        info = self.get_info()
        # 8. rewards: task reward + reward functors
        reward = self._reward(obs, command, info)
        # 9. action terms (post)
        self.last_action = command
        if self._post_terms:
            self.last_action = self.action_manager.process_action(command, "post")
        # 10. dones (``dones`` is None when no env is done)
        terminated, truncated, dones = self._dones(obs, info, diverged)
        # 11. recording
        if self.rollout_buffer is not None:
            self.rollout_buffer.add(obs, action, reward, terminated, truncated, info["success"])
        if self.dataset_manager is not None:
            self.dataset_manager.record_step(obs, action, reward, terminated, truncated, info)
        # 12. autoreset of the done envs (gymnasium SAME_STEP)
        if dones is not None:
            obs = self._auto_reset(obs, dones, info)
        if self._viewer is not None:  # a copy of the state into the viewer's latest-state slot
            self._viewer.after_step(obs, reward, info)
        return obs, reward, terminated, truncated, info

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        """Reset ``options["reset_ids"]`` (all envs by default); ``options["episode_seeds"]``
        replays episodes, ``save_data=False`` discards the finished episodes."""
        options = dict(options or {})
        # 1. seed
        if seed is not None:
            self._seed_rng(seed)
        # 2. the envs to reset
        ids = options.pop("reset_ids", None)
        ids = torch.arange(self.num_envs) if ids is None else torch.as_tensor(ids).reshape(-1).long()
        # 3. dataset: commit (or discard) the episodes that just ended, with their seeds
        self._commit_or_discard(ids, bool(options.get("save_data", True)))
        # 4. episode streams of the new episodes
        self.rng.begin_episodes(ids, episode_seeds_option(options, len(ids)))
        # 5. scene reset: whole state rows (clears a diverged env), then every entity
        if self.rollout_buffer is not None:
            self.rollout_buffer.clear(ids)
        self.scene.reset(ids, keep_uids=self._detached_uids_for_reset)
        # 6. reset events
        self.event_manager.apply("reset", ids)
        # 7. manager resets (interval counters, class functors)
        for manager in (
            self.event_manager,
            self.observation_manager,
            self.reward_manager,
            self.action_manager,
            self.dataset_manager,
        ):
            if manager is not None:
                manager.reset(ids)
        if self._pending_env_keys:  # read by a functor, stored by no event: task code must have set them
            check_after_first_reset(self, self._pending_env_keys)
            self._pending_env_keys = []
        # 8. counters
        rows = ids.cpu()
        self._elapsed_steps[rows] = 0
        self._episode_success[rows] = False
        # 9. observation, info, first-frame recording
        obs = self.get_obs()
        info = self.get_info()
        if self.rollout_buffer is not None:
            self.rollout_buffer.set_first_obs(obs, ids)
        if self.dataset_manager is not None:
            self.dataset_manager.record_reset(obs, ids)
        return obs, info

    # -- phases with more than a line ---------------------------------------------------------------
    def _apply_command(self, command: Any) -> None:
        """Phase 2: a tensor is position targets; a dict routes ``qpos``/``qvel``/``qf``."""
        if isinstance(command, dict):
            for key in ("qpos", "qvel", "qf"):
                if key in command:
                    self._apply_joint_command(key, command[key])
            return
        self._robot_io.write("qpos", command)  # the action itself (no action terms)

    def _apply_joint_command(self, key: str, value: Any) -> None:
        self._robot_io.write(key, value)  # addresses and drive targets resolved at build

    def get_obs(self, **kwargs: Any) -> dict:
        """Phase 6: ``robot`` (active joints' qpos, qvel, qf), ``sensor`` (per uid), then
        the observation functors."""
        obs: dict[str, Any] = {"robot": self._robot_io.observe()}
        if self.sensors:
            obs["sensor"] = {}
            for uid, sensor in self.sensors.items():
                sensor.update()
                obs["sensor"][uid] = sensor.get_data()
        return self.observation_manager.compute(obs) if self._obs_terms else obs

    def _reward(self, obs: Any, command: Any, info: dict) -> torch.Tensor:
        """Phase 8: ``get_reward`` combined with the reward functors (terms in ``info["rewards"]``)."""
        if self._reward_terms:
            # the default task reward is zeros: the terms' sum alone (one op fewer per step)
            base = None if self._default_reward else self._task_reward(obs, command, info)
            reward, terms = self.reward_manager.compute(obs, command, info, base)
            info["rewards"] = terms
            return reward
        return self._task_reward(obs, command, info)

    def _task_reward(self, obs: Any, command: Any, info: dict) -> torch.Tensor:
        reward = self.get_reward(obs, command, info)
        return reward if reward.dtype is torch.float32 else reward.float()

    def _dones(
        self, obs: Any, info: dict, diverged: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, Optional[torch.Tensor]]:
        """Phase 10: :meth:`BaseEnv._dones` (``terminated = success | fail``, none with
        ``ignore_terminations``; ``truncated = check_truncated | time limit | diverged``;
        ``dones`` None when no env is done); a finished episode's success is kept for the
        dataset's commit (reset phase 3)."""
        terminated, truncated, dones = super()._dones(obs, info, diverged)
        if dones is not None:
            episode_success = self._episode_success
            success = info["success"].to(episode_success.device, torch.bool)
            torch.where(dones.to(episode_success.device), success, episode_success, out=episode_success)
        return terminated, truncated, dones

    def _commit_or_discard(self, env_ids: torch.Tensor, save: bool) -> None:
        """Reset phase 3: successful episodes (all with ``save_failed_episodes``) are committed."""
        manager = self.dataset_manager
        if manager is None:
            return
        if not save:
            manager.discard(env_ids)
            return
        if manager.save_failed_episodes:
            keep = torch.ones(len(env_ids), dtype=torch.bool)
        else:
            rows = env_ids.to(self.device)
            keep = (self._episode_success[rows] | self.is_task_success()[rows]).cpu()
        manager.commit(env_ids[keep])
        manager.discard(env_ids[~keep])

    def close(self) -> None:
        """Finalize recorders (never committing partial episodes) and release sensors; idempotent."""
        if self._closed:
            return
        errors: list[Exception] = []
        if self.dataset_manager is not None:
            try:
                self.dataset_manager.finalize()
            except Exception as err:
                errors.append(err)
        super().close()  # the sensors
        if self._viewer is not None:
            self._viewer.close()
        if errors:
            raise errors[0]


_BASE_ENV_HOOKS = ("design_scene", "define_action_space", "apply_action", "step_physics", "reset_envs")
