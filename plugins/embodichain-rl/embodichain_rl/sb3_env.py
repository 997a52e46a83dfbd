"""A Stable-Baselines3 ``VecEnv`` over a batched embodichain env (numpy, CPU).

SB3 treats anything that is not a ``VecEnv`` as one env, and rejects nested ``Dict``
spaces. :class:`Sb3VecEnv` steps all envs of the ``EmbodiedEnv`` in one call and hands SB3:

* observations: the flattened state vector ``(num_envs, D)`` float32 (a ``Box``; use
  ``"MlpPolicy"``), or, when the env has camera images, a one-level dict
  ``{"state": (N, D), <image path>: (N, H, W, C) uint8}`` (use ``"MultiInputPolicy"``);
  see :mod:`embodichain_rl.flatten` for the layout;
* ``dones = terminated | truncated``; the returned row of a finished env is already the
  first observation of its next episode (embodichain resets in the same step);
* per env ``infos[i]``: for finished envs ``terminal_observation`` (the row of
  ``info["final_obs"]``, the observation before the reset), ``TimeLimit.truncated``
  (``truncated and not terminated``: SB3 bootstraps those), ``episode`` ``{"r", "l"}``
  (what SB3's ``Monitor`` adds, for its logger) and ``is_success``.

Example:
    >>> venv = Sb3VecEnv(make_env("PushCube-v1", num_envs=16))  # doctest: +SKIP
    >>> PPO("MlpPolicy", venv).learn(10_000)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Iterable

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from embodichain_rl.episodes import EpisodeTracker, final_success
from embodichain_rl.flatten import ObsFlattener

__all__ = ["Sb3VecEnv"]


class Sb3VecEnv(VecEnv):
    """Stable-Baselines3's ``VecEnv`` interface over an ``EmbodiedEnv`` (module docstring).

    Args:
        env: the batched env (``gym.make(task_id, num_envs=N)``; wrappers are unwrapped).
        flattener: the observation layout (default: from the env's observation space,
            camera images included).
    """

    def __init__(self, env: Any, flattener: ObsFlattener | None = None):
        self.env = env.unwrapped
        self.flattener = flattener or ObsFlattener.from_space(self.env.single_observation_space)
        self.episodes = EpisodeTracker(int(self.env.num_envs))
        self._actions: np.ndarray | None = None
        space = self.env.single_action_space
        action_space = gym.spaces.Box(space.low.astype(np.float32), space.high.astype(np.float32), dtype=np.float32)
        super().__init__(int(self.env.num_envs), self._observation_space(), action_space)

    def _observation_space(self) -> gym.Space:
        if not self.flattener.image_paths:
            return self.flattener.state_space()
        spaces: dict[str, gym.Space] = {"state": self.flattener.state_space()}
        for path, shape in zip(self.flattener.image_paths, self.flattener.image_shapes):
            spaces[path] = gym.spaces.Box(0, 255, shape, np.uint8)
        return gym.spaces.Dict(spaces)

    def to_sb3(self, obs: Any) -> VecEnvObs:
        """A batched embodichain observation in this env's SB3 layout (numpy)."""
        state = self.flattener.state(obs).cpu().numpy()
        if not self.flattener.image_paths:
            return state
        out = {"state": state}
        out.update({path: img.cpu().numpy() for path, img in self.flattener.images(obs).items()})
        return out

    # -- SB3's interface ------------------------------------------------------------------------
    def reset(self) -> VecEnvObs:
        """Reset every env with the seed given to :meth:`seed` (once) and the options of
        :meth:`set_options` for env 0."""
        obs, _ = self.env.reset(seed=self._seeds[0], options=self._options[0] or None)
        self._reset_seeds()
        self._reset_options()
        self.episodes = EpisodeTracker(self.num_envs)
        return self.to_sb3(obs)

    def step_async(self, actions: np.ndarray) -> None:
        """Store ``actions`` ``(num_envs, action_dim)``, clipped to the action space."""
        space: Any = self.action_space
        self._actions = np.clip(np.asarray(actions, dtype=np.float32), space.low, space.high)

    def step_wait(self) -> VecEnvStepReturn:
        """Step every env with the stored actions; see the module docstring for ``infos``."""
        if self._actions is None:
            raise RuntimeError("step_wait() called before step_async()")
        obs, reward, terminated, truncated, info = self.env.step(torch.from_numpy(self._actions))
        self._actions = None
        reward_t = torch.as_tensor(reward, dtype=torch.float32).reshape(self.num_envs)
        terminated, truncated = torch.as_tensor(terminated).bool(), torch.as_tensor(truncated).bool()
        done = terminated | truncated
        infos = self._infos(info, done, truncated & ~terminated, reward_t)
        return self.to_sb3(obs), reward_t.numpy(), done.numpy(), infos

    def _infos(
        self, info: dict[str, Any], done: torch.Tensor, time_out: torch.Tensor, reward: torch.Tensor
    ) -> list[dict[str, Any]]:
        """One dict per env; only finished envs get entries."""
        returns, lengths = self.episodes.returns + reward.double(), self.episodes.lengths + 1
        self.episodes.add(reward, done, info)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        ids = torch.nonzero(done).flatten().tolist()
        if not ids:
            return infos
        final = self.to_sb3(info["final_obs"]) if "final_obs" in info else None
        success = final_success(info, done)
        for i in ids:  # the finished envs only
            terminal = (
                None
                if final is None
                else ({k: v[i] for k, v in final.items()} if isinstance(final, dict) else final[i])
            )
            infos[i] = {
                "terminal_observation": terminal,
                "TimeLimit.truncated": bool(time_out[i]),
                "episode": {"r": float(returns[i]), "l": int(lengths[i])},
                "is_success": bool(success[i]),
            }
        return infos

    def close(self) -> None:
        """Close the env."""
        self.env.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The env's attribute, once per requested env (the envs share one object)."""
        value = getattr(self.env, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of the env (shared by all envs: only for every env at once)."""
        if len(list(self._get_indices(indices))) != self.num_envs:
            raise ValueError(f"set_attr({attr_name!r}) must target every env: the batch is one env object")
        setattr(self.env, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call a method of the env once; its result is repeated per requested env."""
        result = getattr(self.env, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """Always false: the adapter wraps the unwrapped env."""
        return [False for _ in self._get_indices(indices)]

    def _get_indices(self, indices: VecEnvIndices) -> Iterable[int]:
        if indices is None:
            return range(self.num_envs)
        return [indices] if isinstance(indices, int) else list(indices)
