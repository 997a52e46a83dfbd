"""Evaluate a checkpoint (either library): one episode in each of ``num_envs`` envs, run
together, with the policy's mean action (or sampled actions); success is the task's
``success`` at the episode's last step.

Example:
    >>> evaluate(Path("outputs/rl_push_cube/model_1950.pt"), num_envs=100)  # doctest: +SKIP
    {'episodes': 100, 'success_rate': 0.83, 'mean_return': 512.4}
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch

from embodichain_rl.episodes import final_success
from embodichain_rl.outputs import read_meta
from embodichain_rl.play import policy_and_env

__all__ = ["evaluate"]


def evaluate(checkpoint: Path, num_envs: int = 64, seed: int = 1000, deterministic: bool = True) -> dict[str, Any]:
    """Success rate and mean return of one episode per env (``seed``: the env seed, distinct
    from training's by default; ``deterministic``: the mean action, else sampled actions as
    in training)."""
    meta = read_meta(checkpoint)
    adapter, act = policy_and_env(checkpoint, meta, seed, num_envs=num_envs, video=False, deterministic=deterministic)
    env = adapter.env
    obs, _ = env.reset(seed=seed)
    finished = torch.zeros(num_envs, dtype=torch.bool)
    returns, success = torch.zeros(num_envs, dtype=torch.float64), torch.zeros(num_envs, dtype=torch.bool)
    with torch.no_grad():
        while not finished.all():
            obs, reward, terminated, truncated, info = env.step(act(obs))
            returns += torch.as_tensor(reward).double() * ~finished
            done = torch.as_tensor(terminated | truncated).bool() & ~finished
            success |= final_success(info, done) & done
            finished |= done
    adapter.close()
    return {"episodes": num_envs, "success_rate": float(success.float().mean()), "mean_return": float(returns.mean())}
