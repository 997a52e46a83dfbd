"""Train and run Stable-Baselines3 PPO on an embodichain task.

Outputs in ``out``: tensorboard events (``tb/``, when tensorboard is installed; it is a
dependency of this plugin), checkpoints ``checkpoints/ppo_<steps>_steps.zip`` (SB3's
``CheckpointCallback``), the final ``model.zip``, ``embodichain_rl.json`` and ``curve.csv``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from embodichain_rl.env_factory import make_env
from embodichain_rl.flatten import ObsFlattener
from embodichain_rl.outputs import CurveWriter, write_meta
from embodichain_rl.sb3_env import Sb3VecEnv

__all__ = ["default_ppo_kwargs", "train", "load_policy", "play_env"]


def default_ppo_kwargs(num_envs: int, n_steps: int = 32) -> dict[str, Any]:
    """SB3 PPO settings: ``n_steps`` per env per rollout, 4 minibatches, gamma 0.97."""
    return {
        "n_steps": n_steps,
        "batch_size": max(1, n_steps * num_envs // 4),
        "n_epochs": 5,
        "gamma": 0.97,
        "gae_lambda": 0.95,
        "learning_rate": 3e-4,
        "ent_coef": 0.0,
        "clip_range": 0.2,
        "policy_kwargs": {"net_arch": [256, 256]},
    }


def _tensorboard_dir(out: Path) -> str | None:
    try:
        import tensorboard  # noqa: F401
    except ImportError:
        return None  # SB3 then logs to stdout only
    return str(out / "tb")


def train(
    task: str,
    num_envs: int,
    steps: int,
    seed: int,
    out: Path,
    max_episode_steps: int = 0,
    ppo_kwargs: dict[str, Any] | None = None,
    threads: int = 1,
    log: Callable[[str], None] = print,
) -> Path:
    """Train PPO for ``steps`` env steps (all envs); return the final ``model.zip``.

    ``ppo_kwargs`` default to :func:`default_ppo_kwargs`; ``threads`` sets torch's intra-op
    threads (0 leaves torch's default).
    """
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import CheckpointCallback

    if threads > 0:
        import torch

        torch.set_num_threads(threads)
    out.mkdir(parents=True, exist_ok=True)
    venv = Sb3VecEnv(make_env(task, num_envs, seed=seed, max_episode_steps=max_episode_steps))
    venv.seed(seed)
    kwargs = ppo_kwargs or default_ppo_kwargs(num_envs)
    policy = "MultiInputPolicy" if venv.flattener.image_paths else "MlpPolicy"
    write_meta(
        out,
        task=task,
        library="sb3",
        flattener=venv.flattener,
        num_envs=num_envs,
        seed=seed,
        max_episode_steps=int(venv.env.max_episode_steps),
        policy=policy,
    )
    log(f"SB3 PPO ({policy}) on {task}: {num_envs} envs, {steps} steps, observations {venv.observation_space}")
    model = PPO(policy, venv, seed=seed, device="cpu", tensorboard_log=_tensorboard_dir(out), verbose=1, **kwargs)
    save_freq = max(1, kwargs["n_steps"] * 10)  # per env: every 10 rollouts
    callback = CheckpointCallback(save_freq=save_freq, save_path=str(out / "checkpoints"), name_prefix="ppo")
    curve, started = CurveWriter(out / "curve.csv"), time.perf_counter()
    model.learn(total_timesteps=steps, callback=[callback, _CurveCallback(venv, curve, started)])
    path = out / "model.zip"
    model.save(str(path))
    venv.close()
    return path


def _CurveCallback(venv: Sb3VecEnv, curve: CurveWriter, started: float) -> Any:  # noqa: N802 - a class factory
    from stable_baselines3.common.callbacks import BaseCallback

    class CurveCallback(BaseCallback):
        """Writes a curve row at the end of every rollout."""

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            curve.add(self.num_timesteps, round(time.perf_counter() - started, 2), venv.episodes.pop())

    return CurveCallback()


def load_policy(checkpoint: Path, deterministic: bool = True) -> Callable[[Any], np.ndarray]:
    """The policy of an SB3 PPO ``.zip`` (its mean action with ``deterministic``): numpy
    observations -> actions, clipped to the action space by SB3's ``predict``."""
    from stable_baselines3 import PPO

    model = PPO.load(str(checkpoint), device="cpu")
    return lambda obs: model.predict(obs, deterministic=deterministic)[0]


def play_env(task: str, meta: dict[str, Any], seed: int, video: bool, num_envs: int = 1) -> Sb3VecEnv:
    """An adapter with the training run's observation layout (and a camera with ``video``)."""
    env = make_env(task, num_envs, seed=seed, max_episode_steps=int(meta.get("max_episode_steps", 0)), video=video)
    return Sb3VecEnv(env, flattener=ObsFlattener.from_dict(meta["flattener"]))
