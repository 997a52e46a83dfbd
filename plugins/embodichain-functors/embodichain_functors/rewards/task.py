"""Task rewards ``f(env, obs, action, info) -> (N,)``: the task's own success flag."""

from __future__ import annotations

from typing import Any

import torch

__all__ = ["success_reward"]


def success_reward(env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
    """1 where ``info["success"]``, else 0 (0 everywhere when the key is missing).

    Args:
        env: the env.
        obs, action: step data (unused).
        info: the step info.

    Example:
        ``{"func": "success_reward", "weight": 10.0}``
    """
    success = info.get("success") if isinstance(info, dict) else None
    if success is None:
        return torch.zeros(env.num_envs)
    return torch.as_tensor(success).reshape(-1).float().expand(env.num_envs).clone()
