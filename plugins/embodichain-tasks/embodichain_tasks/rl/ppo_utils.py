"""Building blocks of :mod:`embodichain_tasks.rl.ppo`: observation flattening and
normalisation, the actor-critic network and the learning-curve writers."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import torch
from torch import nn
from torch.distributions import Normal

__all__ = ["flatten_obs", "RunningNorm", "ActorCritic", "write_curve", "plot_curve"]


def flatten_obs(obs: Any, skip: Sequence[str] = ("sensor",)) -> torch.Tensor:
    """Concatenate every tensor leaf of a (nested) batched observation into (N, D).

    Keys are visited in sorted order, so the layout is stable; ``skip`` drops
    top-level sections (camera images by default).
    """
    leaves: list[torch.Tensor] = []

    def walk(node: Any, top: bool) -> None:
        if isinstance(node, dict):
            for key in sorted(node):
                if not (top and key in skip):
                    walk(node[key], False)
        elif node is not None:
            value = torch.as_tensor(node).float()
            leaves.append(value.reshape(value.shape[0], -1))

    walk(obs, True)
    return torch.cat(leaves, dim=-1)


class RunningNorm:
    """Running mean/variance observation normaliser (parallel Welford), clipped to +-10."""

    def __init__(self, dim: int, clip: float = 10.0):
        self.mean = torch.zeros(dim, dtype=torch.float64)
        self.var = torch.ones(dim, dtype=torch.float64)
        self.count = 1e-4
        self.clip = clip

    def __call__(self, x: torch.Tensor, update: bool = True) -> torch.Tensor:
        if update:
            self._update(x.to(torch.float64))
        out = (x - self.mean.float()) / (self.var.float().sqrt() + 1e-8)
        return out.clamp(-self.clip, self.clip)

    def _update(self, x: torch.Tensor) -> None:
        batch_mean, batch_var, n = x.mean(0), x.var(0, unbiased=False), x.shape[0]
        delta, total = batch_mean - self.mean, self.count + n
        self.mean = self.mean + delta * n / total
        self.var = (self.var * self.count + batch_var * n + delta.pow(2) * self.count * n / total) / total
        self.count = total

    def state_dict(self) -> dict[str, Any]:
        return {"mean": self.mean, "var": self.var, "count": self.count}


def _layer(i: int, o: int, gain: float = math.sqrt(2)) -> nn.Linear:
    layer = nn.Linear(i, o)
    nn.init.orthogonal_(layer.weight, gain)
    nn.init.zeros_(layer.bias)
    return layer


class ActorCritic(nn.Module):
    """Gaussian MLP policy (state-independent log std) and an MLP value function."""

    def __init__(self, obs_dim: int, act_dim: int, hidden: int = 256, init_log_std: float = -0.5):
        super().__init__()
        self.critic = nn.Sequential(
            _layer(obs_dim, hidden), nn.Tanh(), _layer(hidden, hidden), nn.Tanh(), _layer(hidden, 1, 1.0)
        )
        self.actor = nn.Sequential(
            _layer(obs_dim, hidden), nn.Tanh(), _layer(hidden, hidden), nn.Tanh(), _layer(hidden, act_dim, 0.01)
        )
        self.log_std = nn.Parameter(torch.full((act_dim,), init_log_std))

    def value(self, obs: torch.Tensor) -> torch.Tensor:
        return self.critic(obs).squeeze(-1)

    def _dist(self, obs: torch.Tensor) -> Normal:
        return Normal(self.actor(obs), self.log_std.exp().expand(obs.shape[0], -1))

    def act(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Sample ``(action, log_prob, value)``."""
        dist = self._dist(obs)
        action = dist.sample()
        return action, dist.log_prob(action).sum(-1), self.value(obs)

    def evaluate(self, obs: torch.Tensor, action: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``(log_prob, entropy, value)`` of given actions."""
        dist = self._dist(obs)
        return dist.log_prob(action).sum(-1), dist.entropy().sum(-1), self.value(obs)

    def deterministic(self, obs: torch.Tensor) -> torch.Tensor:
        """The mean action."""
        return self.actor(obs)


def write_curve(out: Path, curve: list[dict[str, Any]], title: str) -> None:
    """``curve.csv``, ``curve.json`` and ``learning_curve.png`` in ``out``."""
    if curve:
        with open(out / "curve.csv", "w", newline="", encoding="utf-8") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(curve[0]))
            writer.writeheader()
            writer.writerows(curve)
    (out / "curve.json").write_text(json.dumps(curve, indent=1) + "\n", encoding="utf-8")
    plot_curve(out / "learning_curve.png", curve, title)


def _smooth(values: np.ndarray, window: int) -> np.ndarray:
    if window <= 1 or len(values) < window:
        return values
    kernel = np.ones(window) / window
    padded = np.concatenate([np.full(window - 1, values[0]), values])
    return np.convolve(padded, kernel, mode="valid")


def plot_curve(path: Path, curve: list[dict[str, Any]], title: str) -> None:
    """Mean episode return against env steps (raw and smoothed); matplotlib when
    installed, else :func:`~embodichain_tasks.rl.png_plot.line_plot_png`."""
    rows = [r for r in curve if r.get("mean_return") is not None]
    if not rows:
        return
    x = np.array([r["env_steps"] for r in rows], dtype=float)
    y = np.array([r["mean_return"] for r in rows], dtype=float)
    smooth = _smooth(y, max(1, len(y) // 15))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        from embodichain_tasks.rl.png_plot import line_plot_png

        Path(path).write_bytes(
            line_plot_png(
                [x, x],
                [y, smooth],
                title=title,
                xlabel="env steps",
                ylabel="mean episode return",
                labels=["per iteration", "smoothed"],
            )
        )
        return
    fig, ax = plt.subplots(figsize=(9, 5.6), dpi=100)
    ax.plot(x, y, label="per iteration", alpha=0.6)
    ax.plot(x, smooth, label="smoothed")
    ax.set(title=title, xlabel="env steps", ylabel="mean episode return")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.savefig(path)
    plt.close(fig)
