"""One env of a batch as a plain, unbatched numpy ``gymnasium.Env``.

``EmbodiedEnv`` is batched even with ``num_envs=1`` (leading dim 1, torch tensors, its own
autoreset). :class:`SingleEnvView` wraps a ``num_envs=1`` env the way single-env tools
expect (gymnasium's and Stable-Baselines3's ``check_env``, ``DummyVecEnv``):

* observations in the :class:`~embodichain_rl.flatten.ObsFlattener` layout without the
  batch dim: a float32 state vector, or ``{"state", <image path>...}`` with cameras;
* ``reward`` a float, ``terminated``/``truncated`` bools, ``info`` with ``success`` (bool);
* the observation returned with ``terminated or truncated`` is the episode's last one
  (``info["final_obs"]``), not the next episode's first: call ``reset()`` as with any
  gymnasium env.

Example:
    >>> view = SingleEnvView(make_env("PushCube-v1", num_envs=1))  # doctest: +SKIP
    >>> gymnasium.utils.env_checker.check_env(view)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch

from embodichain_rl.flatten import ObsFlattener

__all__ = ["SingleEnvView"]


class SingleEnvView(gym.Env):
    """An unbatched numpy view of a ``num_envs=1`` ``EmbodiedEnv`` (module docstring).

    Args:
        env: the env; it must have ``num_envs == 1``.
        flattener: the observation layout (default: from the env's observation space).
    """

    def __init__(self, env: Any, flattener: ObsFlattener | None = None):
        self.env = env.unwrapped
        if int(self.env.num_envs) != 1:
            raise ValueError(f"SingleEnvView needs an env with num_envs=1, got num_envs={self.env.num_envs}")
        self.flattener = flattener or ObsFlattener.from_space(self.env.single_observation_space)
        space = self.env.single_action_space
        self.action_space = gym.spaces.Box(
            space.low.astype(np.float32), space.high.astype(np.float32), dtype=np.float32
        )
        self.observation_space = self._observation_space()
        self.metadata = {"render_modes": [], "render_fps": self.env.metadata.get("render_fps", 25)}
        self.render_mode = None

    def _observation_space(self) -> gym.Space:
        state = self.flattener.state_space()
        if not self.flattener.image_paths:
            return state
        spaces: dict[str, gym.Space] = {"state": state}
        for path, shape in zip(self.flattener.image_paths, self.flattener.image_shapes):
            spaces[path] = gym.spaces.Box(0, 255, shape, np.uint8)
        return gym.spaces.Dict(spaces)

    def _obs(self, obs: Any) -> Any:
        state = self.flattener.state(obs)[0].cpu().numpy()
        if not self.flattener.image_paths:
            return state
        out = {"state": state}
        out.update({path: img[0].cpu().numpy() for path, img in self.flattener.images(obs).items()})
        return out

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        """Reset the env (``seed`` reseeds it)."""
        super().reset(seed=seed)
        obs, info = self.env.reset(seed=seed, options=options)
        return self._obs(obs), {"success": bool(torch.as_tensor(info["success"]).reshape(-1)[0])}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Step the env with an ``(action_dim,)`` action."""
        action = torch.as_tensor(np.asarray(action, dtype=np.float32)).reshape(1, -1)
        obs, reward, terminated, truncated, info = self.env.step(action)
        done = bool(torch.as_tensor(terminated | truncated).reshape(-1)[0])
        if done and "final_obs" in info:
            obs = info["final_obs"]
        source = info.get("final_info", info) if done else info
        out_info = {"success": bool(torch.as_tensor(source["success"]).reshape(-1)[0])}
        return (
            self._obs(obs),
            float(torch.as_tensor(reward).reshape(-1)[0]),
            bool(torch.as_tensor(terminated).reshape(-1)[0]),
            bool(torch.as_tensor(truncated).reshape(-1)[0]),
            out_info,
        )

    def close(self) -> None:
        """Close the env."""
        self.env.close()
