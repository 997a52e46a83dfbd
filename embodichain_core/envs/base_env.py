"""``BaseEnv``: the batched gymnasium env without managers, for tasks with custom simulation logic.

A subclass writes its step in a few overrides, which :meth:`BaseEnv.step` calls in this order:

1. :meth:`~BaseEnv.apply_action`: the checked action (float32 ``(num_envs, action_dim)``)
   into the simulation;
2. :meth:`~BaseEnv.step_physics`: ``sim_steps_per_control`` physics steps of every env
   (override it to act between physics steps);
3. :meth:`~BaseEnv.get_obs`: the batched observation;
4. ``compute_task_state`` (success, fail, metrics) and ``get_reward(obs, action, info)``;
5. the dones: ``terminated = success | fail``, ``truncated = check_truncated | time limit |
   diverged``; then the done envs reset in the same call (gymnasium ``SAME_STEP``).

Construction: the config (:meth:`~BaseEnv.check_cfg`), the scene
(:meth:`~BaseEnv.design_scene`, then compiled), :meth:`~BaseEnv.on_scene_built`, the action
space (:meth:`~BaseEnv.define_action_space`), the first observation and the spaces.
:meth:`~BaseEnv.reset_envs` resets a subset of envs. :class:`~embodichain_core.envs.embodied_env.EmbodiedEnv`
is a ``BaseEnv`` built the same way: it implements these overrides from its config and
writes its own ``step`` and ``reset`` from the same phases (it calls ``apply_action``,
``step_physics`` and ``reset_envs`` there).
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Optional

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode

from embodichain_core.config.validate import check_backend, check_run_settings, check_sim
from embodichain_core.envs import env_build
from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.envs.cfg import EnvCfg
from embodichain_core.envs.episode_rng import EpisodeRandom, episode_seeds_option
from embodichain_core.envs.spaces import batch_space, space_from_obs
from embodichain_core.envs.summary import print_summary
from embodichain_core.envs.task_api import TaskApi
from embodichain_core.envs.timing import resolve_num_envs, resolve_timing
from embodichain_core.sim.scene import Scene

__all__ = ["BaseEnv"]


class BaseEnv(TaskApi, gym.Env):
    """A batched env built from an :class:`EnvCfg` and the scene of :meth:`design_scene`.

    Every observation, reward and flag has a leading ``num_envs`` dimension. Overrides:
    ``design_scene``, ``define_action_space``, ``apply_action``, ``get_obs`` (required);
    ``check_cfg``, ``on_scene_built``, ``step_physics``, ``compute_task_state``,
    ``get_reward``, ``check_truncated``, ``reset_envs`` (optional). See
    docs/embodied_env.md, "BaseEnv".

    Random generators, all seeded from ``cfg.seed`` (docs/embodied_env.md, "Seeding and
    determinism"):

    * ``rng``: the per-env, per-episode streams (:class:`EpisodeRandom`, one row per env of
      ``env_ids``). Use it for what a reset or a functor draws: an episode replays from its
      seed whatever the other envs do.
    * ``generator``: one shared CPU ``torch.Generator``, for torch draws that are not per env
      and episode (a script's random actions).
    * ``np_random``: gymnasium's ``numpy.random.Generator`` of the env (``gym.Env.np_random``),
      the same kind of shared stream for numpy.

    Example:
        >>> env = MySliderEnv(EnvCfg(num_envs=4, seed=0))  # doctest: +SKIP
        >>> obs, info = env.reset()  # doctest: +SKIP
        >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())  # doctest: +SKIP
    """

    metadata: dict[str, Any] = {"render_modes": [], "autoreset_mode": AutoresetMode.SAME_STEP}
    cfg_cls: type = EnvCfg
    cfg: Any
    single_action_space: gym.spaces.Box
    _check_action: ActionChecker

    def __init__(
        self,
        cfg: Optional[EnvCfg] = None,
        num_envs: Optional[int] = None,
        render_mode: Optional[str] = None,
        **kwargs: Any,
    ):
        if render_mode is not None and render_mode not in type(self).metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of {type(self).metadata['render_modes']}")
        self._init_run(cfg, num_envs, render_mode, kwargs)
        self.check_cfg()
        self.scene = Scene(self.cfg.sim_cfg, self.num_envs, str(self.device))
        self.sensors = self.scene.sensors  # filled as design_scene adds them
        try:
            self._build_task()
        except BaseException:
            self.close()  # nothing half-built stays open (sensors' renderers)
            raise
        if self.cfg.verbose:
            print_summary(self)

    def _build_task(self) -> None:
        """The task's scene, its action space, the first observation and the spaces."""
        self.design_scene(self.scene)
        self.scene.build()
        self.on_scene_built()
        space = self.define_action_space()
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
            raise TypeError(
                f"{type(self).__name__}.define_action_space must return a 1-D gym.spaces.Box, got {space!r}"
            )
        self.single_action_space = space
        self._init_obs = self.get_obs()  # the spaces' sample (and a viewer's first frame)
        self._init_spaces(self._init_obs)
        self._check_action = self._action_checker()

    def _action_checker(self) -> ActionChecker:
        """The boundary check of ``step``: one flat action of the action space's width."""
        return ActionChecker(self.num_envs, [self.single_action_space.shape[0]], self.device, self.action_space)

    # -- what EmbodiedEnv shares ----------------------------------------------------------------
    def _init_run(self, cfg: Any, num_envs: Optional[int], render_mode: Optional[str], overrides: dict) -> None:
        """The config (a copy, keyword ``overrides`` set), timing, device, seed, counters."""
        self._closed = False
        self.affordance_datas: dict[str, Any] = {}
        self._detached_uids_for_reset: list[str] = []
        self.cfg = env_build.resolve_cfg(type(self), cfg, overrides)
        check_backend(self.cfg.sim_cfg, "sim_cfg")  # backend and device, before anything uses the device
        self.metadata = dict(type(self).metadata)
        self.render_mode = render_mode
        self._num_envs = resolve_num_envs(self.cfg, num_envs)
        self.physics_dt, self.sim_steps_per_control = resolve_timing(self.cfg)
        self.step_dt = self.physics_dt * self.sim_steps_per_control
        self.metadata["render_fps"] = self.control_frequency
        sim_device = self.cfg.sim_cfg.sim_device
        on_warp = self.cfg.sim_cfg.backend == "warp"  # its tensors live on sim_device
        self.device = torch.device(sim_device if sim_device != "cuda" or on_warp else "cpu")
        self._seed_rng(self.cfg.seed)
        self.max_episode_steps = int(self.cfg.max_episode_steps) if self.cfg.max_episode_steps > 0 else 2**31 - 1
        self._elapsed_steps = torch.zeros(self.num_envs, dtype=torch.int32, device=self.device)
        # the dones ask the task for truncations only when it overrides check_truncated (the default has none)
        self._task_truncates = type(self).check_truncated is not TaskApi.check_truncated

    def _init_spaces(self, obs: Any) -> None:
        """Observation spaces from the first observation; the batched action space."""
        self.single_observation_space = space_from_obs(obs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def _seed_rng(self, seed: Optional[int]) -> None:
        """Seed the episode streams ``env.rng``, ``env.generator`` and ``env.np_random`` (see the
        class docstring for which to use for what)."""
        if seed is None or seed == -1:
            seed = int.from_bytes(os.urandom(4), "little") >> 1
        self.cfg.seed = int(seed)
        self.generator = torch.Generator().manual_seed(int(seed))
        self._np_random, self._np_random_seed = np.random.default_rng(int(seed)), int(seed)  # gym.Env.np_random
        if getattr(self, "rng", None) is None:
            self.rng = EpisodeRandom(self.num_envs, int(seed))
        else:
            self.rng.seed(int(seed))

    def _auto_reset(self, obs: Any, dones: torch.Tensor, info: dict) -> Any:
        """Reset the done envs; the terminal step stays in ``info`` (``final_obs``,
        ``final_info``, the mask ``_final_obs``)."""
        info["final_obs"] = obs
        info["final_info"] = {k: v for k, v in info.items() if k not in ("final_obs",)}
        info["_final_obs"] = dones.clone()
        done_ids = torch.from_numpy(np.flatnonzero(dones.cpu().numpy()))  # env ids live on the CPU
        new_obs, _ = self.reset(options={"reset_ids": done_ids})
        return new_obs

    @property
    def out_of_space_actions(self) -> int:
        """Env-steps so far whose action had a value outside the action space."""
        return int(self._check_action.out_of_space)

    def close(self) -> None:
        """Release the sensors; idempotent."""
        if self._closed:
            return
        self._closed = True
        for sensor in getattr(self, "sensors", {}).values():
            sensor.close()

    # -- the loop --------------------------------------------------------------------------------
    def step(self, action: Any) -> tuple[Any, torch.Tensor, torch.Tensor, torch.Tensor, dict]:  # type: ignore[override]
        """One control step of every env (the phases of the module docstring)."""
        # 1. action: checked once (a bad one is one clear error), then into the simulation
        action = self._check_action(action)
        self.apply_action(action)
        # 2. physics; this step counts from here on
        diverged = self.step_physics()
        self._elapsed_steps += 1
        # 3. observation
        obs = self.get_obs()
        # 4. task state, info and reward
        info = self.get_info()
        reward = self.get_reward(obs, action, info).to(torch.float32)
        # 5. dones, then the autoreset of the done envs
        terminated, truncated, dones = self._dones(obs, info, diverged)
        if dones is not None:
            obs = self._auto_reset(obs, dones, info)
        return obs, reward, terminated, truncated, info

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[Any, dict]:
        """Reset ``options["reset_ids"]`` (all envs by default); ``options["episode_seeds"]``
        (one per reset env) replays episodes."""
        options = dict(options or {})
        ids = self._reset_ids(seed, options)  # the seed, then the envs to reset
        self._begin_episodes(ids, options)
        self.reset_envs(ids)
        self._elapsed_steps[ids.cpu()] = 0
        return self.get_obs(), self.get_info()

    def _reset_ids(self, seed: Optional[int], options: dict) -> torch.Tensor:
        """The first reset phases: reseed with ``seed`` (``None`` keeps the streams); the envs
        to reset, ``options["reset_ids"]`` (popped; all envs by default), as a long tensor."""
        if seed is not None:
            self._seed_rng(seed)
        ids = options.pop("reset_ids", None)
        return torch.arange(self.num_envs) if ids is None else torch.as_tensor(ids).reshape(-1).long()

    def _begin_episodes(self, ids: torch.Tensor, options: dict) -> None:
        """The episode streams of the new episodes of ``ids``: from ``options["episode_seeds"]``
        (one per id) when given, else ``env.rng``'s rule."""
        self.rng.begin_episodes(ids, episode_seeds_option(options, len(ids)))

    def _dones(self, obs: Any, info: dict, diverged: Any) -> tuple[torch.Tensor, torch.Tensor, Optional[torch.Tensor]]:
        """``terminated = success | fail`` (none with ``ignore_terminations``); ``truncated =
        check_truncated | time limit | diverged`` (``diverged``: a bool mask, or env ids);
        ``dones`` (None: no env is done). The step's one host read: the done and diverged
        flags, copied together."""
        success, fail = info["success"], info["fail"]
        terminated = torch.zeros_like(success) if self.cfg.ignore_terminations else success | fail
        if not isinstance(diverged, torch.Tensor):  # ids, from a task's own step_physics
            ids, diverged = diverged, torch.zeros(self.num_envs, dtype=torch.bool)
            diverged[list(ids)] = True
        diverged = diverged.to(terminated.device)
        info["diverged"] = diverged
        truncated = (self._elapsed_steps >= self.max_episode_steps).to(terminated.device) | diverged
        if self._task_truncates:
            truncated = self.check_truncated(obs, info).to(truncated.device) | truncated
        dones = terminated | truncated
        any_done, any_diverged = torch.stack((dones, diverged)).any(dim=1).tolist()
        if any_diverged:
            ids = torch.nonzero(diverged.cpu()).flatten().tolist()
            warnings.warn(f"simulation diverged in env(s) {ids}; resetting them", RuntimeWarning, stacklevel=3)
        return terminated, truncated, dones if any_done else None

    # -- the overrides of a BaseEnv task ---------------------------------------------------------
    def check_cfg(self) -> None:
        """Check the config before anything is built: required fields, the run settings and
        ``sim_cfg``. A task with settings of its own extends it (``super().check_cfg()``
        first) and raises :class:`~embodichain_core.config.errors.ConfigError` naming the key."""
        self.cfg.validate()
        check_run_settings(self.cfg)
        check_sim(self.cfg.sim_cfg, "sim_cfg")

    def design_scene(self, scene: Scene) -> None:
        """Add the task's entities to ``scene`` (``scene.add_robot``, ``add_rigid_object``,
        ``add_light``, ...); the env builds it afterwards. Required."""
        raise NotImplementedError(f"{type(self).__name__} must override design_scene(scene) to add its entities")

    def on_scene_built(self) -> None:
        """Called once the scene is compiled (``self.sim`` exists), before the action space and
        the first observation: resolve what needs the built model (joint addresses, entity
        handles, per-env tensors sized by it). Optional; nothing by default."""

    def define_action_space(self) -> gym.spaces.Box:
        """The action space of one env: a 1-D ``gym.spaces.Box``. Required."""
        raise NotImplementedError(f"{type(self).__name__} must override define_action_space() (a 1-D Box)")

    def apply_action(self, action: torch.Tensor) -> None:
        """Write the checked action (float32 ``(num_envs, action_dim)``, not clipped) into
        the simulation, e.g. as joint targets. Required."""
        raise NotImplementedError(f"{type(self).__name__} must override apply_action(action)")

    def step_physics(self) -> Any:
        """``sim_steps_per_control`` physics steps of every env; returns the diverged envs: a
        ``(num_envs,)`` bool mask (``sim.advance``, no host wait on a GPU) or a list of ids."""
        return self.scene.sim.advance(self.sim_steps_per_control)

    def get_obs(self, **kwargs: Any) -> Any:
        """The batched observation: a tensor or a (nested) dict of tensors, leading ``num_envs``. Required."""
        raise NotImplementedError(f"{type(self).__name__} must override get_obs()")

    def reset_envs(self, env_ids: torch.Tensor) -> None:
        """Reset the envs ``env_ids`` (a long tensor): by default every entity goes back to
        its initial state, except those excluded with ``add_detached_uids_for_reset``. Draw
        per-episode randomness from ``self.rng`` (one row per id)."""
        self.scene.reset(env_ids, keep_uids=self._detached_uids_for_reset)
