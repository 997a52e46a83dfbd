"""``EmbodiedEnv``: the batched, configuration-driven env (leading ``num_envs`` dim everywhere).

It is a :class:`~embodichain_core.envs.base_env.BaseEnv` whose overrides come from the
config (helpers in :mod:`embodichain_core.envs.env_build`): ``check_cfg`` (the whole config,
the manager sections), ``design_scene`` (the config's entities), ``on_scene_built`` (robot,
active joints, managers), ``define_action_space``, ``apply_action`` (the command into the
joint drives), ``get_obs`` and ``reset_envs`` (scene reset, reset events, manager resets).
:meth:`EmbodiedEnv.step` and :meth:`EmbodiedEnv.reset` each read top to bottom, one
named phase after the other, calling those overrides and ``step_physics``;
docs/embodied_env.md lists the same phases with the same numbers. ``step`` auto-resets
finished envs in the same call (gymnasium ``AutoresetMode.SAME_STEP``): the terminal
observation is in ``info["final_obs"]`` with the mask ``info["_final_obs"]``.
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium as gym
import torch
from gymnasium.vector import AutoresetMode

from embodichain_core.envs import env_build
from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.envs.base_env import BaseEnv
from embodichain_core.envs.cfg import EmbodiedEnvCfg
from embodichain_core.envs.robot_io import RobotIO
from embodichain_core.envs.rollout_buffer import RolloutBuffer
from embodichain_core.envs.scene_setup import add_config_entities
from embodichain_core.envs.task_api import TaskApi
from embodichain_core.managers.env_keys import check_after_first_reset
from embodichain_core.sim.scene import Scene
from embodichain_core.viewing import attach_viewer


class EmbodiedEnv(BaseEnv):
    """The configuration-driven env (see docs/embodied_env.md).

    It builds through :class:`BaseEnv`'s ``__init__`` with the overrides of the module
    docstring, and runs its own ``step`` and ``reset`` from BaseEnv's phases. A subclass
    overrides the task points (``compute_task_state``, ``get_reward``, ...) and may extend
    BaseEnv's others, calling ``super()``: ``step_physics`` to act between physics steps,
    ``apply_action`` (it receives the command after the action terms), ``design_scene``,
    ``reset_envs``.

    Example:
        >>> env = gym.make("MyTask-v0", cfg=MyTaskCfg(num_envs=4))
        >>> obs, info = env.reset(seed=0)
        >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.SAME_STEP}
    cfg_cls: type = EmbodiedEnvCfg
    # set during construction (env_build)
    single_action_space: gym.spaces.Box  # joint-position limits, or the action manager's ``pre`` terms
    robot: Any
    active_joint_ids: list[int]
    event_manager: Any
    observation_manager: Any
    reward_manager: Any
    action_manager: Any
    dataset_manager: Any
    _robot_io: RobotIO
    _check_action: ActionChecker  # env_build.action_checker

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
        self._default_reward = type(self).get_reward is TaskApi.get_reward  # zeros: phase 8 skips it
        # config, scene, managers, spaces, the action check, the summary (BaseEnv, with the overrides below)
        super().__init__(cfg, num_envs, render_mode, **kwargs)
        try:
            if self.cfg.init_rollout_buffer or env_build.recorders_need_buffer(self.dataset_manager):
                self.cfg.init_rollout_buffer = True
                self.rollout_buffer = RolloutBuffer(
                    self._init_obs, self.single_action_space.shape, self.num_envs, self.max_episode_steps
                )
            self._viewer = attach_viewer(self)
        except BaseException:
            self.close()  # nothing half-built stays open (sensors, recorders)
            raise

    # -- BaseEnv's construction overrides, from the config -------------------------------------------
    def check_cfg(self) -> None:
        """The whole config (:meth:`EmbodiedEnvCfg.validate`, the memory estimate included) and
        the manager sections, each functor resolved once for the build; then ``extensions``."""
        self._functors = env_build.check_cfg(self)

    def design_scene(self, scene: Scene) -> None:
        """The config's entities, then the scene hooks of the event functors (``modify_scene``)."""
        add_config_entities(self.cfg, scene, self._functors["events"])

    def on_scene_built(self) -> None:
        """The robot, the active joints, then the managers (and the ``startup`` events)."""
        self._joint_space = env_build.resolve_robot(self)
        self._episode_success = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
        env_build.build_managers(self, self._functors)
        self._functors = {}  # the managers hold what they use
        # which manager phases have work (managers are fixed once built): one flag test per step
        self._pre_terms = bool(len(self.action_manager))
        self._post_terms = bool(self.action_manager.terms("post"))
        self._obs_terms = bool(len(self.observation_manager))
        self._reward_terms = bool(len(self.reward_manager))

    def define_action_space(self) -> gym.spaces.Box:
        """The ``pre`` action terms' bounds, else the active joints' position limits."""
        space = self.action_manager.single_action_space()
        return self._joint_space if space is None else space

    def _action_checker(self) -> ActionChecker:
        """The boundary check of ``step``: the action terms' widths, or joint commands."""
        return env_build.action_checker(self)

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
        self.apply_action(command)
        # 3. physics: sim_steps_per_control physics steps of every env (sim.advance)
        diverged = self.step_physics()
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
        # 1. seed (with ``seed``)
        # 2. the envs to reset (BaseEnv's first phases)
        ids = self._reset_ids(seed, options)
        # 3. dataset: commit (or discard) the episodes that just ended, with their seeds
        self._commit_or_discard(ids, bool(options.get("save_data", True)))
        # 4. episode streams of the new episodes
        self._begin_episodes(ids, options)
        # 5. scene reset: whole state rows (clears a diverged env), then every entity
        # 6. reset events
        # 7. manager resets (interval counters, class functors): 5-7 are reset_envs
        self.reset_envs(ids)
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
    def apply_action(self, command: Any) -> None:
        """Phase 2: the command (the action after the ``pre`` action terms) into the joint
        drives. A tensor is position targets; a dict routes ``qpos``/``qvel``/``qf``."""
        robot_io = self._robot_io  # addresses and drive targets resolved at build
        if isinstance(command, dict):
            for key in ("qpos", "qvel", "qf"):
                if key in command:
                    robot_io.write(key, command[key])
            return
        robot_io.write("qpos", command)  # the action itself (no action terms)

    def reset_envs(self, env_ids: torch.Tensor) -> None:
        """Reset phases 5-7: the rollout-buffer rows, the scene (BaseEnv's: every entity but
        the detached ones), the reset events, each manager's reset, for ``env_ids``."""
        if self.rollout_buffer is not None:
            self.rollout_buffer.clear(env_ids)
        super().reset_envs(env_ids)
        self.event_manager.apply("reset", env_ids)
        for manager in (
            self.event_manager,
            self.observation_manager,
            self.reward_manager,
            self.action_manager,
            self.dataset_manager,
        ):
            if manager is not None:
                manager.reset(env_ids)
        if self._pending_env_keys:  # read by a functor, stored by no event: task code must have set them
            check_after_first_reset(self, self._pending_env_keys)
            self._pending_env_keys = []

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
