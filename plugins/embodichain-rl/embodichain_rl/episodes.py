"""Episode statistics of a batched env: returns, lengths and success of finished episodes.

An episode's success is ``info["success"]`` at its last step: the value in
``info["final_info"]`` (the info before the autoreset), the step's ``info`` otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

__all__ = ["EpisodeTracker", "EpisodeStats"]


@dataclass
class EpisodeStats:
    """Aggregates of the episodes finished since the last :meth:`EpisodeTracker.pop`."""

    episodes: int
    mean_return: float | None
    mean_length: float | None
    success_rate: float | None


def final_success(info: dict[str, Any], done: torch.Tensor) -> torch.Tensor:
    """``(N,)`` bool: the success flag of each env's last step (rows of ``done`` matter)."""
    final = info.get("final_info") if isinstance(info.get("final_info"), dict) else None
    source = final if final is not None and "success" in final else info
    if "success" not in source:
        return torch.zeros_like(done, dtype=torch.bool)
    return torch.as_tensor(source["success"]).bool().reshape(done.shape)


class EpisodeTracker:
    """Running per-env returns and lengths, vectorized (no per-env loop per step).

    Args:
        num_envs: envs of the batch.
    """

    def __init__(self, num_envs: int):
        self.returns = torch.zeros(num_envs, dtype=torch.float64)
        self.lengths = torch.zeros(num_envs, dtype=torch.long)
        self._done: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def add(self, reward: torch.Tensor, done: torch.Tensor, info: dict[str, Any]) -> None:
        """Count one step; record the envs whose episode ended (``done``)."""
        done = torch.as_tensor(done).bool().cpu()
        self.returns += torch.as_tensor(reward).double().cpu()
        self.lengths += 1
        if done.any():
            success = final_success(info, done).cpu()
            self._done.append(
                (self.returns[done].numpy().copy(), self.lengths[done].numpy().copy(), success[done].numpy().copy())
            )
            self.returns[done] = 0.0
            self.lengths[done] = 0

    def pop(self) -> EpisodeStats:
        """Stats of the episodes finished since the last call (``None`` values when none)."""
        if not self._done:
            return EpisodeStats(0, None, None, None)
        returns, lengths, success = (np.concatenate(parts) for parts in zip(*self._done))
        self._done = []
        return EpisodeStats(len(returns), float(returns.mean()), float(lengths.mean()), float(success.mean()))
