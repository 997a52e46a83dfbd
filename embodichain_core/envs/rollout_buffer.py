"""Per-env episode buffer (``init_rollout_buffer=True``): frames ``(N, T, ...)``.

Frame ``t`` of env ``i`` holds the observation the policy saw and the action it
took from it (``obs_t, action_t``), then the reward and flags of that step. Each
env has its own cursor; a reset of env ``i`` clears its row after the dataset
manager has committed it. Recorders read ``env.rollout_buffer`` instead of
keeping their own copies.

Example:
    >>> buf = env.rollout_buffer
    >>> n = int(buf.length[0]); buf.data["actions"][0, :n]  # env 0's episode so far
"""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.config.errors import ConfigError


def _flatten(obs: Any, prefix: str = "") -> dict[str, torch.Tensor]:
    if isinstance(obs, dict):
        out: dict[str, torch.Tensor] = {}
        for key, value in obs.items():
            out.update(_flatten(value, f"{prefix}/{key}" if prefix else key))
        return out
    return {prefix: obs}


class RolloutBuffer:
    """Preallocated per-env episode storage."""

    def __init__(self, obs: dict, action_shape: tuple, num_envs: int, max_steps: int):
        if max_steps >= 2**31 - 1 or max_steps <= 0:
            raise ConfigError("init_rollout_buffer", "a rollout buffer needs a finite max_episode_steps")
        self.num_envs, self.max_steps = num_envs, max_steps
        n, t = num_envs, max_steps
        self.data: dict[str, torch.Tensor] = {
            f"obs/{k}": torch.zeros((n, t) + tuple(v.shape[1:]), dtype=v.dtype) for k, v in _flatten(obs).items()
        }
        self.data["actions"] = torch.zeros((n, t) + tuple(action_shape), dtype=torch.float32)
        self.data["rewards"] = torch.zeros(n, t)
        for flag in ("terminated", "truncated", "success"):
            self.data[flag] = torch.zeros(n, t, dtype=torch.bool)
        self.length = torch.zeros(n, dtype=torch.long)
        self._pending_obs = {k: v.clone() for k, v in _flatten(obs).items()}

    def set_first_obs(self, obs: dict, env_ids: torch.Tensor) -> None:
        """The observation new episodes of ``env_ids`` start from."""
        for key, value in _flatten(obs).items():
            self._pending_obs[key][env_ids] = value[env_ids]

    def add(
        self,
        obs_next: dict,
        action: Any,
        reward: torch.Tensor,
        terminated: torch.Tensor,
        truncated: torch.Tensor,
        success: torch.Tensor,
    ) -> None:
        """Store one frame per env (envs whose episode is full keep their last frame)."""
        rows = torch.arange(self.num_envs)
        t = self.length.clamp(max=self.max_steps - 1)
        for key, value in self._pending_obs.items():
            self.data[f"obs/{key}"][rows, t] = value
        if (
            isinstance(action, torch.Tensor)
            and action.dim() == 2
            and action.shape[1:] == self.data["actions"].shape[2:]
        ):
            self.data["actions"][rows, t] = action.float()
        self.data["rewards"][rows, t] = reward.float()
        self.data["terminated"][rows, t] = terminated
        self.data["truncated"][rows, t] = truncated
        self.data["success"][rows, t] = success
        self.length = (self.length + 1).clamp(max=self.max_steps)
        for key, value in _flatten(obs_next).items():
            self._pending_obs[key] = value.clone()

    def episode(self, env_id: int) -> dict[str, torch.Tensor]:
        """The frames of env ``env_id``'s current episode."""
        n = int(self.length[env_id])
        return {k: v[env_id, :n] for k, v in self.data.items()}

    def clear(self, env_ids: torch.Tensor) -> None:
        self.length[env_ids] = 0
