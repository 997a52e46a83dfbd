"""Train and run rsl_rl PPO (``OnPolicyRunner``) on an embodichain task.

Outputs in ``out``: rsl_rl's tensorboard events and checkpoints ``model_<it>.pt`` (every
``save_interval`` iterations and at the end), ``embodichain_rl.json`` (task, library,
observation layout, the runner config: what ``--play`` needs) and ``curve.csv`` (per
iteration: env steps, finished episodes, mean return, success rate).
"""

from __future__ import annotations

import copy
import math
import time
from pathlib import Path
from typing import Any, Callable

import torch

from embodichain_rl.env_factory import make_env
from embodichain_rl.episodes import EpisodeStats
from embodichain_rl.flatten import ObsFlattener
from embodichain_rl.outputs import CurveWriter, write_meta
from embodichain_rl.rsl_rl_env import RslRlVecEnv

__all__ = ["default_train_cfg", "train", "load_policy"]


def default_train_cfg(num_steps_per_env: int = 24, save_interval: int = 50) -> dict[str, Any]:
    """rsl_rl 5.x runner config: PPO, 3x256 ELU MLP actor and critic with observation
    normalization, a scalar Gaussian std, both reading the ``"policy"`` group."""
    mlp = {"class_name": "MLPModel", "hidden_dims": [256, 256, 256], "activation": "elu", "obs_normalization": True}
    return {
        "num_steps_per_env": num_steps_per_env,
        "save_interval": save_interval,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "algorithm": {
            "class_name": "PPO",
            "num_learning_epochs": 5,
            "num_mini_batches": 4,
            "learning_rate": 1e-3,
            "schedule": "adaptive",
            "desired_kl": 0.01,
            "gamma": 0.97,
            "lam": 0.95,
            "entropy_coef": 0.005,
            "clip_param": 0.2,
            "max_grad_norm": 1.0,
            "value_loss_coef": 1.0,
        },
        "actor": {
            **mlp,
            "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": 1.0, "std_type": "scalar"},
        },
        "critic": copy.deepcopy(mlp),
        "logger": "tensorboard",
    }


def train(
    task: str,
    num_envs: int,
    steps: int,
    seed: int,
    out: Path,
    max_episode_steps: int = 0,
    train_cfg: dict[str, Any] | None = None,
    threads: int = 1,
    log: Callable[[str], None] = print,
) -> Path:
    """Train for at least ``steps`` env steps (all envs); return the last checkpoint.

    Args:
        task: the task id.
        num_envs: envs simulated together.
        steps: env steps of all envs; iterations = ``ceil(steps / (num_envs * num_steps_per_env))``.
        seed: env and torch seed.
        out: output directory (created).
        max_episode_steps: episode limit; 0 keeps the task's.
        train_cfg: the runner config (default :func:`default_train_cfg`).
        threads: torch intra-op threads for the networks (0 leaves torch's default; the
            small MLPs gain nothing from more, MuJoCo's batch uses the cores).
        log: where progress lines go.
    """
    from rsl_rl.runners import OnPolicyRunner

    torch.manual_seed(seed)
    if threads > 0:
        torch.set_num_threads(threads)
    cfg = train_cfg or default_train_cfg()
    out.mkdir(parents=True, exist_ok=True)
    curve, started = CurveWriter(out / "curve.csv"), time.perf_counter()

    def on_stats(env_steps: int, stats: EpisodeStats) -> None:
        curve.add(env_steps, round(time.perf_counter() - started, 2), stats)

    env = make_env(task, num_envs, seed=seed, max_episode_steps=max_episode_steps)
    vec = RslRlVecEnv(env, on_stats=on_stats, stats_every=cfg["num_steps_per_env"])
    write_meta(
        out,
        task=task,
        library="rsl_rl",
        flattener=vec.flattener,
        train_cfg=cfg,
        num_envs=num_envs,
        seed=seed,
        max_episode_steps=vec.max_episode_length,
    )
    iterations = max(1, math.ceil(steps / (num_envs * cfg["num_steps_per_env"])))
    log(f"rsl_rl PPO on {task}: {num_envs} envs, {iterations} iterations, observations {vec.flattener.state_dim}")
    runner = OnPolicyRunner(vec, copy.deepcopy(cfg), log_dir=str(out), device="cpu")
    runner.learn(iterations)
    vec.close()
    return out / f"model_{runner.current_learning_iteration}.pt"


def load_policy(checkpoint: Path, vec: RslRlVecEnv, train_cfg: dict[str, Any]) -> Callable[..., torch.Tensor]:
    """The inference policy of an rsl_rl checkpoint, for ``vec``'s observations:
    ``policy(obs)`` is the mean action, ``policy(obs, stochastic_output=True)`` a sample."""
    from rsl_rl.runners import OnPolicyRunner

    runner = OnPolicyRunner(vec, copy.deepcopy(train_cfg), log_dir=None, device="cpu")
    runner.load(str(checkpoint), map_location="cpu")
    return runner.get_inference_policy(device="cpu")


def play_env(task: str, meta: dict[str, Any], seed: int, video: bool, num_envs: int = 1) -> RslRlVecEnv:
    """An adapter with the training run's observation layout (and a camera with ``video``)."""
    env = make_env(task, num_envs, seed=seed, max_episode_steps=int(meta.get("max_episode_steps", 0)), video=video)
    return RslRlVecEnv(env, flattener=ObsFlattener.from_dict(meta["flattener"]))
