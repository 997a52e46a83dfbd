"""An ``rsl_rl.env.VecEnv`` over a batched embodichain env (rsl-rl-lib 5.x).

rsl_rl never resets the env (the env autoresets, as embodichain's does in the same step),
reads observations as a ``TensorDict`` of 2-D groups and bootstraps time-outs from
``extras["time_outs"]``. :class:`RslRlVecEnv` gives it:

* ``obs["policy"]``: the flattened state vector ``(num_envs, D)`` (see
  :mod:`embodichain_rl.flatten`: sorted leaf paths, camera images left out), and one group
  per image leaf, ``obs[<path>]`` ``(num_envs, H, W, C)`` uint8, for a ``CNNModel``;
* ``dones = terminated | truncated`` and ``extras["time_outs"] = truncated & ~terminated``
  (episode limits, a cube off the table, divergence: not failures of the policy);
* ``extras["log"]``: ``/success`` (fraction of envs succeeding this step) for rsl_rl's logger;
* ``episode_length_buf``: the env's step counters (rsl_rl may write random starts into it).

rsl_rl collects rollouts under ``torch.inference_mode()``; the adapter steps the env outside
it, so the env's own state (functor buffers created during a step) stays usable by a later
``reset()`` or plain-mode code.

rsl_rl bootstraps a time-out with the value of the observation it stored *before* the step,
so the final observation (``info["final_obs"]``) is not needed here.

Example:
    >>> vec = RslRlVecEnv(make_env("PushCube-v1", num_envs=64))  # doctest: +SKIP
    >>> obs = vec.get_observations(); obs["policy"].shape  # doctest: +SKIP
    torch.Size([64, 34])
"""

from __future__ import annotations

from typing import Any, Callable

import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from embodichain_rl.episodes import EpisodeStats, EpisodeTracker
from embodichain_rl.flatten import ObsFlattener

__all__ = ["RslRlVecEnv"]


class RslRlVecEnv(VecEnv):
    """rsl_rl's ``VecEnv`` interface over an ``EmbodiedEnv`` (module docstring).

    Args:
        env: the batched env (``gym.make(task_id, num_envs=N)``; wrappers are unwrapped).
        clip_actions: when set, actions are clamped to ``+-clip_actions`` before the env's
            own bounds; in any case they are clamped to the env's action space.
        flattener: the observation layout (default: from the env's observation space,
            without ``"sensor"`` images).
        on_stats: called as ``on_stats(env_steps, stats)`` every ``stats_every`` steps with
            the :class:`~embodichain_rl.episodes.EpisodeStats` of the episodes finished since
            the last call (``env_steps`` counts steps of all envs).
        stats_every: steps between two ``on_stats`` calls (rsl_rl's ``num_steps_per_env``
            gives one call per iteration).
    """

    def __init__(
        self,
        env: Any,
        clip_actions: float | None = None,
        flattener: ObsFlattener | None = None,
        on_stats: Callable[[int, EpisodeStats], None] | None = None,
        stats_every: int = 0,
    ):
        self.env = env.unwrapped
        self.num_envs = int(self.env.num_envs)
        self.device = self.env.device
        self.num_actions = int(self.env.single_action_space.shape[0])
        self.max_episode_length = int(self.env.max_episode_steps)
        self.cfg = self.env.cfg
        self.flattener = flattener or ObsFlattener.from_space(self.env.single_observation_space, skip=("sensor",))
        space = self.env.single_action_space
        low, high = torch.as_tensor(space.low, dtype=torch.float32), torch.as_tensor(space.high, dtype=torch.float32)
        if clip_actions is not None:
            low, high = low.clamp_min(-clip_actions), high.clamp_max(clip_actions)
        self._low, self._high = low.to(self.device), high.to(self.device)
        self.episodes = EpisodeTracker(self.num_envs)
        self.on_stats, self.stats_every, self.steps = on_stats, int(stats_every), 0
        self._obs = self.to_tensordict(self.env.reset()[0])

    # -- rsl_rl's interface -----------------------------------------------------------------------
    @property
    def episode_length_buf(self) -> torch.Tensor:
        """The env's per-env step counters (``env.elapsed_steps``)."""
        return self.env.elapsed_steps

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        self.env.elapsed_steps[:] = torch.as_tensor(value).to(self.env.elapsed_steps.dtype)

    def get_observations(self) -> TensorDict:
        """The current observation groups (the env is reset once, in ``__init__``)."""
        return self._obs

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor, dict[str, Any]]:
        """Step every env with ``actions`` ``(num_envs, num_actions)``.

        Returns:
            ``(obs, rewards (N,), dones (N,) long, extras)``; ``extras["time_outs"]`` (N,) bool.
        """
        with torch.inference_mode(False):  # rsl_rl steps under inference mode: keep the env's own state
            obs, reward, terminated, truncated, info = self.env.step(self.clip(actions).clone())  # normal tensors
        reward = torch.as_tensor(reward, dtype=torch.float32).reshape(self.num_envs)
        terminated, truncated = torch.as_tensor(terminated).bool(), torch.as_tensor(truncated).bool()
        self.episodes.add(reward, terminated | truncated, info)
        self.steps += 1
        if self.on_stats is not None and self.stats_every > 0 and self.steps % self.stats_every == 0:
            self.on_stats(self.steps * self.num_envs, self.episodes.pop())
        self._obs = self.to_tensordict(obs)
        extras = {
            "time_outs": truncated & ~terminated,
            "log": {"/success": torch.as_tensor(info["success"]).float().mean()},
        }
        return self._obs, reward, (terminated | truncated).long(), extras

    def clip(self, actions: torch.Tensor) -> torch.Tensor:
        """``actions`` as float32, clamped to the action space (and ``clip_actions``)."""
        return torch.max(torch.min(torch.as_tensor(actions, dtype=torch.float32), self._high), self._low)

    # -- passthroughs -----------------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> TensorDict:
        """Reset every env (rsl_rl itself never calls this)."""
        self._obs = self.to_tensordict(self.env.reset(seed=seed)[0])
        return self._obs

    def close(self) -> None:
        """Close the env."""
        self.env.close()

    @property
    def unwrapped(self) -> Any:
        """The ``EmbodiedEnv``."""
        return self.env

    def to_tensordict(self, obs: Any) -> TensorDict:
        groups = {"policy": self.flattener.state(obs).to(self.device)}
        groups.update(self.flattener.images(obs))
        return TensorDict(groups, batch_size=[self.num_envs])
