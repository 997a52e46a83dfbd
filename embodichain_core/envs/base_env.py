"""``BaseEnv``: a batched gymnasium env (leading ``num_envs`` dim everywhere).

Subclasses build the scene (:meth:`_setup_scene`), define observations, rewards
and task state. ``step`` auto-resets finished envs in the same call
(gymnasium ``AutoresetMode.SAME_STEP``): the terminal observation is in
``info["final_obs"]`` with the mask ``info["_final_obs"]``.
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Optional

import gymnasium as gym
import numpy as np
import torch
from gymnasium.vector import AutoresetMode

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.envs.cfg import EnvCfg
from embodichain_core.envs.episode_rng import EpisodeRandom
from embodichain_core.envs.spaces import batch_space, space_from_obs
from embodichain_core.envs.timing import resolve_num_envs, resolve_timing
from embodichain_core.utils.suggest import did_you_mean


class BaseEnv(gym.Env):
    """Batched env base. ``cfg_cls`` is the config class used when no cfg is given."""

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.SAME_STEP}
    cfg_cls: type = EnvCfg

    def __init__(self, cfg: Optional[EnvCfg] = None, num_envs: Optional[int] = None,
                 render_mode: Optional[str] = None, **kwargs: Any):
        self.cfg = self._resolve_cfg(cfg, kwargs)
        self.metadata = dict(type(self).metadata)
        self.render_mode = render_mode
        self._num_envs = resolve_num_envs(self.cfg, num_envs)
        self.physics_dt, self.sim_steps_per_control = resolve_timing(self.cfg)
        self.step_dt = self.physics_dt * self.sim_steps_per_control
        self.metadata["render_fps"] = self.control_frequency
        self.device = torch.device(self.cfg.sim_cfg.sim_device if self.cfg.sim_cfg.sim_device != "cuda" else "cpu")
        self._seed_rng(self.cfg.seed)
        self.max_episode_steps = int(self.cfg.max_episode_steps) if self.cfg.max_episode_steps > 0 else 2**31 - 1
        self._elapsed_steps = torch.zeros(self.num_envs, dtype=torch.int32)
        self._episode_success = torch.zeros(self.num_envs, dtype=torch.bool)
        self._closed = False
        self._setup_scene()
        self._init_sim_state()
        obs = self.get_obs()
        self.single_observation_space = space_from_obs(obs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._check_action = self._action_checker()
        self._init_obs = obs

    # -- config --------------------------------------------------------------------------------
    def _resolve_cfg(self, cfg: Optional[EnvCfg], overrides: dict) -> EnvCfg:
        registered_limit = overrides.pop("_registered_max_episode_steps", None)
        if cfg is None:
            cfg = self.cfg_cls()
        elif isinstance(cfg, dict):
            cfg = self.cfg_cls.from_dict(cfg)
        else:
            cfg = cfg.copy()
        if registered_limit is not None and cfg.max_episode_steps == EnvCfg().max_episode_steps:
            cfg.max_episode_steps = int(registered_limit)
        names = {f for f in cfg.__dataclass_fields__}
        for key, value in overrides.items():
            if key not in names:
                raise ConfigError(key, f"unknown env argument {key!r}.{did_you_mean(key, names)}")
            setattr(cfg, key, value)
        return cfg

    def _seed_rng(self, seed: Optional[int]) -> None:
        if seed is None or seed == -1:
            seed = int.from_bytes(os.urandom(4), "little") >> 1
        self.cfg.seed = int(seed)
        self.generator = torch.Generator().manual_seed(int(seed))
        self.np_random_generator = np.random.default_rng(int(seed))
        self._np_random = self.np_random_generator
        if getattr(self, "rng", None) is None:
            self.rng = EpisodeRandom(self.num_envs, int(seed))
        else:
            self.rng.seed(int(seed))

    @property
    def episode_seeds(self) -> np.ndarray:
        """Each env's current episode seed (uint64, ``(num_envs,)``): the key of its
        random stream (``env.rng``), recorded with the episode for exact replay."""
        return self.rng.episode_seeds

    # -- sizes and timing ----------------------------------------------------------------------
    @property
    def num_envs(self) -> int:
        return self._num_envs

    @property
    def control_frequency(self) -> float:
        return 1.0 / self.step_dt

    @property
    def physics_frequency(self) -> float:
        return 1.0 / self.physics_dt

    sim_freq = physics_frequency
    control_freq = control_frequency

    @property
    def elapsed_steps(self) -> torch.Tensor:
        return self._elapsed_steps

    @property
    def unwrapped(self) -> "BaseEnv":
        return self

    def _action_checker(self) -> ActionChecker:
        """The boundary check of :meth:`step` (see :mod:`embodichain_core.envs.action_check`)."""
        width = int(np.prod(self.single_action_space.shape))
        return ActionChecker(self.num_envs, [width], self.device, self.action_space)

    # -- hooks for subclasses -----------------------------------------------------------------
    def _setup_scene(self) -> None:
        raise NotImplementedError

    def _init_sim_state(self) -> None:
        """Build managers; runs after the scene exists, before the first observation."""

    def _preprocess_action(self, action: Any) -> Any:
        return action

    def _step_action(self, action: Any) -> Any:
        raise NotImplementedError

    def _physics_step(self) -> list[int]:
        raise NotImplementedError

    def _update_sim_state(self) -> None:
        """Runs after physics, before observations (interval events)."""

    def _postprocess_action(self, action: Any) -> Any:
        return action

    def get_obs(self, **kwargs: Any) -> dict:
        raise NotImplementedError

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        """Task override point: ``(success, fail, metrics)``, (N,) bool each."""
        zeros = torch.zeros(self.num_envs, dtype=torch.bool)
        return zeros, zeros.clone(), {}

    def get_info(self, **kwargs: Any) -> dict:
        success, fail, metrics = self.compute_task_state(**kwargs)
        return {"success": success, "fail": fail, "elapsed_steps": self._elapsed_steps.clone(), "metrics": metrics}

    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        """Task reward before reward functors (zeros by default)."""
        return torch.zeros(self.num_envs, dtype=torch.float32)

    def check_truncated(self, obs: Any, info: dict) -> torch.Tensor:
        """Task-specific truncation (none by default)."""
        return torch.zeros(self.num_envs, dtype=torch.bool)

    def is_task_success(self, **kwargs: Any) -> torch.Tensor:
        """Whether each env's current state counts as a success (for dataset saving)."""
        return self.compute_task_state(**kwargs)[0]

    def evaluate(self, **kwargs: Any) -> dict:
        """Per-env ``success`` plus metrics (every env, not only env 0)."""
        info = self.get_info(**kwargs)
        return {"success": info["success"], "fail": info["fail"], **info["metrics"]}

    def _reset_envs(self, env_ids: torch.Tensor, options: dict) -> None:
        raise NotImplementedError

    def _after_step(self, obs: Any, action: Any, reward: torch.Tensor, terminated: torch.Tensor,
                    truncated: torch.Tensor, info: dict) -> None:
        """Hook after termination is known and before auto-reset (recording)."""

    # -- gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None) -> tuple[dict, dict]:
        """Reset ``options["reset_ids"]`` (all envs by default); other options go to the
        reset logic (e.g. ``save_data=False`` discards the finished episodes)."""
        options = dict(options or {})
        if seed is not None:
            self._seed_rng(seed)
        ids = options.pop("reset_ids", None)
        ids = torch.arange(self.num_envs) if ids is None else torch.as_tensor(ids).reshape(-1).long()
        self._reset_envs(ids, options)
        self._elapsed_steps[ids] = 0
        self._episode_success[ids] = False
        obs = self.get_obs()
        return obs, self.get_info()

    def step(self, action: Any) -> tuple[dict, torch.Tensor, torch.Tensor, torch.Tensor, dict]:
        """One control step of every env; ``action`` follows the rule of
        :mod:`embodichain_core.envs.action_check` (a bad action is one clear error)."""
        action = self._check_action(action)
        command = self._preprocess_action(action)
        self._step_action(command)
        diverged = self._physics_step()
        self._update_sim_state()
        self._elapsed_steps += 1
        obs = self.get_obs()
        info = self.get_info()
        reward = self._compute_reward(obs, command, info)
        self.last_action = self._postprocess_action(command)
        terminated = info["success"] | info["fail"]
        if self.cfg.ignore_terminations:
            terminated = torch.zeros_like(terminated)
        truncated = self.check_truncated(obs, info) | (self._elapsed_steps >= self.max_episode_steps)
        truncated = truncated | self._mark_diverged(diverged, info)
        dones = terminated | truncated
        self._episode_success[dones] = info["success"][dones]
        self._after_step(obs, action, reward, terminated, truncated, info)
        if dones.any():
            obs = self._auto_reset(obs, dones, info)
        return obs, reward, terminated, truncated, info

    def _compute_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return self.get_reward(obs, action, info)

    def _mark_diverged(self, diverged: list[int], info: dict) -> torch.Tensor:
        mask = torch.zeros(self.num_envs, dtype=torch.bool)
        if diverged:
            mask[diverged] = True
            warnings.warn(f"simulation diverged in env(s) {diverged}; resetting them", RuntimeWarning, stacklevel=3)
        info["diverged"] = mask
        return mask

    def _auto_reset(self, obs: Any, dones: torch.Tensor, info: dict) -> Any:
        info["final_obs"] = obs
        info["final_info"] = {k: v for k, v in info.items() if k not in ("final_obs",)}
        info["_final_obs"] = dones.clone()
        ids = torch.nonzero(dones).flatten()
        new_obs, _ = self.reset(options={"reset_ids": ids})
        return new_obs

    def close(self) -> None:
        self._closed = True
