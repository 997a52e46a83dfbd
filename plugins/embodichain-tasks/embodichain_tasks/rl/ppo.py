"""PPO in pure torch for batched embodichain envs (default task: ``PushCube-v1``).

A compact clipped-PPO (CleanRL style): a Gaussian MLP policy and value net,
running observation normalisation, GAE with time-limit bootstrapping (the value of
``info["final_obs"]`` for truncated envs), and per-iteration logging of the mean
return and success rate of the episodes finished in that iteration. Writes to
``--out``: ``curve.csv`` and ``curve.json`` (the learning curve),
``learning_curve.png`` and ``policy.pt``.

Example:
    $ python -m embodichain_tasks.rl.ppo --num_envs 64 --total_steps 640000 --out outputs/ppo
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
import torch
from torch import nn

from embodichain_tasks.rl.ppo_utils import ActorCritic, RunningNorm, flatten_obs, write_curve

__all__ = ["PPOConfig", "train", "main"]


@dataclass
class PPOConfig:
    """Training settings (the CLI flags of the same names).

    ``max_episode_steps`` 0 keeps the task's limit; ``threads`` sets torch's intra-op
    threads (1: the networks are small, MuJoCo's batch stepping uses the cores).
    """

    task: str = "PushCube-v1"
    num_envs: int = 64
    max_episode_steps: int = 0
    total_steps: int = 640_000
    num_steps: int = 50
    lr: float = 3e-4
    gamma: float = 0.97
    gae_lambda: float = 0.95
    update_epochs: int = 4
    minibatches: int = 4
    clip_coef: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: int = 256
    seed: int = 0
    out: str = "outputs/ppo"
    threads: int = 1
    quiet: bool = False


@dataclass
class Rollout:
    """One iteration's batch, (T, N, ...) each."""

    obs: torch.Tensor
    actions: torch.Tensor
    logprobs: torch.Tensor
    rewards: torch.Tensor
    dones: torch.Tensor
    values: torch.Tensor
    returns: torch.Tensor = field(default_factory=lambda: torch.empty(0))
    advantages: torch.Tensor = field(default_factory=lambda: torch.empty(0))


class EpisodeStats:
    """Per-env running returns; collects the finished episodes' returns and successes."""

    def __init__(self, num_envs: int):
        self.running = torch.zeros(num_envs)
        self.returns: list[float] = []
        self.successes: list[bool] = []

    def add(self, reward: torch.Tensor, done: torch.Tensor, success: torch.Tensor) -> None:
        self.running += reward
        for i in torch.nonzero(done).flatten().tolist():
            self.returns.append(float(self.running[i]))
            self.successes.append(bool(success[i]))
            self.running[i] = 0.0

    def pop(self) -> tuple[Optional[float], Optional[float], int]:
        """(mean return, success rate, episode count) since the last call."""
        n = len(self.returns)
        out = (float(np.mean(self.returns)), float(np.mean(self.successes)), n) if n else (None, None, 0)
        self.returns, self.successes = [], []
        return out


def make_env(cfg: PPOConfig) -> Any:
    """The batched env (quiet construction)."""
    import gymnasium as gym

    import embodichain_core  # noqa: F401  (loads the plugins: registers the task ids)
    from embodichain_core.envs import EmbodiedEnv

    kwargs: dict[str, Any] = {"num_envs": cfg.num_envs, "seed": cfg.seed, "verbose": False}
    if cfg.max_episode_steps > 0:  # through the cfg: gym.make keeps a max_episode_steps kwarg for itself
        entry = gym.spec(cfg.task).entry_point
        creator = gym.envs.registration.load_env_creator(entry) if isinstance(entry, str) else entry
        if not (isinstance(creator, type) and issubclass(creator, EmbodiedEnv)):
            raise TypeError(f"task {cfg.task!r} is no EmbodiedEnv: max_episode_steps is set through its cfg_cls")
        kwargs["cfg"] = creator.cfg_cls(max_episode_steps=cfg.max_episode_steps)
    return gym.make(cfg.task, **kwargs).unwrapped


def collect(
    env: Any, agent: ActorCritic, norm: RunningNorm, obs: torch.Tensor, cfg: PPOConfig, stats: EpisodeStats
) -> tuple[Rollout, torch.Tensor]:
    """Step ``cfg.num_steps`` times; return the rollout and the next (normalised) observation."""
    buf: dict[str, list[torch.Tensor]] = {k: [] for k in ("obs", "actions", "logprobs", "rewards", "dones", "values")}
    low, high = env.single_action_space.low, env.single_action_space.high
    for _ in range(cfg.num_steps):
        with torch.no_grad():
            action, logprob, value = agent.act(obs)
        clipped = torch.clamp(action, torch.as_tensor(low), torch.as_tensor(high))
        raw, reward, terminated, truncated, info = env.step(clipped)
        done = terminated | truncated
        stats.add(reward.float(), done, info["success"])
        reward = reward.float() + _bootstrap(agent, norm, info, truncated & ~terminated, cfg.gamma)
        for key, val in zip(buf, (obs, action, logprob, reward, done.float(), value)):
            buf[key].append(val)
        obs = norm(flatten_obs(raw))
    return Rollout(**{k: torch.stack(v) for k, v in buf.items()}), obs


def _bootstrap(agent: ActorCritic, norm: RunningNorm, info: dict, cut: torch.Tensor, gamma: float) -> torch.Tensor:
    """``gamma * V(final_obs)`` where an episode was cut by the time limit (else 0)."""
    if not cut.any() or "final_obs" not in info:
        return torch.zeros(cut.shape)
    with torch.no_grad():
        return gamma * agent.value(norm(flatten_obs(info["final_obs"]), update=False)) * cut.float()


def compute_gae(batch: Rollout, next_value: torch.Tensor, cfg: PPOConfig) -> None:
    """Fill ``batch.advantages`` and ``batch.returns`` (GAE-lambda)."""
    steps = batch.rewards.shape[0]
    adv = torch.zeros_like(batch.rewards)
    last = torch.zeros_like(next_value)
    for t in reversed(range(steps)):
        nxt = next_value if t == steps - 1 else batch.values[t + 1]
        live = 1.0 - batch.dones[t]
        delta = batch.rewards[t] + cfg.gamma * nxt * live - batch.values[t]
        last = delta + cfg.gamma * cfg.gae_lambda * live * last
        adv[t] = last
    batch.advantages, batch.returns = adv, adv + batch.values


def update(agent: ActorCritic, optim: torch.optim.Optimizer, batch: Rollout, cfg: PPOConfig) -> dict[str, float]:
    """PPO epochs over shuffled minibatches; return the last losses."""
    flat = {
        k: getattr(batch, k).reshape(-1, *getattr(batch, k).shape[2:])
        for k in ("obs", "actions", "logprobs", "advantages", "returns")
    }
    size = flat["obs"].shape[0]
    mb = max(1, size // cfg.minibatches)
    out: dict[str, float] = {}
    for _ in range(cfg.update_epochs):
        perm = torch.randperm(size)
        for start in range(0, size, mb):
            idx = perm[start : start + mb]
            logprob, entropy, value = agent.evaluate(flat["obs"][idx], flat["actions"][idx])
            ratio = (logprob - flat["logprobs"][idx]).exp()
            adv = flat["advantages"][idx]
            adv = (adv - adv.mean()) / (adv.std() + 1e-8)
            pg = torch.max(-adv * ratio, -adv * ratio.clamp(1 - cfg.clip_coef, 1 + cfg.clip_coef)).mean()
            v_loss = 0.5 * (value - flat["returns"][idx]).pow(2).mean()
            loss = pg + cfg.vf_coef * v_loss - cfg.ent_coef * entropy.mean()
            optim.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(agent.parameters(), cfg.max_grad_norm)
            optim.step()
            out = {"policy_loss": pg.item(), "value_loss": v_loss.item(), "entropy": entropy.mean().item()}
    return out


def train(cfg: PPOConfig) -> list[dict[str, Any]]:
    """Train PPO on ``cfg.task``; write the curve, plot and policy to ``cfg.out``; return the curve."""
    torch.manual_seed(cfg.seed)
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    env = make_env(cfg)
    raw, _ = env.reset(seed=cfg.seed)
    norm = RunningNorm(flatten_obs(raw).shape[-1])
    obs = norm(flatten_obs(raw))
    agent = ActorCritic(obs.shape[-1], env.single_action_space.shape[0], cfg.hidden)
    optim = torch.optim.Adam(agent.parameters(), lr=cfg.lr, eps=1e-5)
    stats, curve = EpisodeStats(cfg.num_envs), []
    iterations = max(1, cfg.total_steps // (cfg.num_steps * cfg.num_envs))
    started = time.perf_counter()
    for it in range(1, iterations + 1):
        for group in optim.param_groups:  # linear learning-rate annealing
            group["lr"] = cfg.lr * (1.0 - (it - 1) / iterations)
        batch, obs = collect(env, agent, norm, obs, cfg, stats)
        with torch.no_grad():
            compute_gae(batch, agent.value(obs), cfg)
        losses = update(agent, optim, batch, cfg)
        mean_return, success, episodes = stats.pop()
        row = {
            "iteration": it,
            "env_steps": it * cfg.num_steps * cfg.num_envs,
            "wall_s": round(time.perf_counter() - started, 2),
            "episodes": episodes,
            "mean_return": mean_return,
            "success_rate": success,
            **losses,
        }
        curve.append(row)
        if not cfg.quiet:
            ret = "-" if mean_return is None else f"{mean_return:8.2f}"
            rate = "-" if success is None else f"{success:5.2f}"
            print(
                f"iter {it:4d}/{iterations}  steps {row['env_steps']:8d}  {row['wall_s']:7.1f}s  "
                f"return {ret}  success {rate}  episodes {episodes}",
                flush=True,
            )
    env.close()
    save_outputs(cfg, curve, agent, norm)
    return curve


def save_outputs(cfg: PPOConfig, curve: list[dict[str, Any]], agent: ActorCritic, norm: RunningNorm) -> None:
    """Write ``curve.csv``, ``curve.json``, ``learning_curve.png`` and ``policy.pt`` to ``cfg.out``."""
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    write_curve(out, curve, f"PPO {cfg.task} ({cfg.num_envs} envs)")
    (out / "config.json").write_text(json.dumps(asdict(cfg), indent=2) + "\n", encoding="utf-8")
    torch.save({"agent": agent.state_dict(), "obs_norm": norm.state_dict(), "config": asdict(cfg)}, out / "policy.pt")


def build_parser() -> argparse.ArgumentParser:
    """CLI flags: one per :class:`PPOConfig` field."""
    parser = argparse.ArgumentParser(prog="python -m embodichain_tasks.rl.ppo", description=__doc__.splitlines()[0])
    for name, value in asdict(PPOConfig()).items():
        if isinstance(value, bool):
            parser.add_argument(f"--{name}", action="store_true")
        else:
            parser.add_argument(f"--{name}", type=type(value), default=value)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Parse the flags, train, print where the outputs are."""
    cfg = PPOConfig(**vars(build_parser().parse_args(argv)))
    curve = train(cfg)
    returns = [row["mean_return"] for row in curve if row["mean_return"] is not None]
    if returns:
        print(f"mean return: first {returns[0]:.2f}, last {returns[-1]:.2f}; outputs in {cfg.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
