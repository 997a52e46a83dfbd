"""Run a trained policy (either library) in one env and write an mp4 of its episodes.

The env gets an extra camera (:data:`~embodichain_rl.env_factory.VIDEO_CAMERA`); the
policy sees the observation layout stored with the checkpoint, so the camera does not
change its input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch

from embodichain_rl.env_factory import VIDEO_CAMERA
from embodichain_rl.outputs import read_meta, write_mp4

__all__ = ["play", "policy_and_env"]


def _frame(obs: Any) -> np.ndarray:
    return obs["sensor"][VIDEO_CAMERA]["color"][0].cpu().numpy()


def policy_and_env(
    checkpoint: Path, meta: dict[str, Any], seed: int, num_envs: int = 1, video: bool = True, deterministic: bool = True
) -> tuple[Any, Callable[[Any], torch.Tensor]]:
    """The adapter (``num_envs`` envs, a video camera with ``video``) and
    ``act(raw_obs) -> (num_envs, A)``: the checkpoint's policy, its mean action (``deterministic``)
    or a sample of its action distribution, clipped to the action space as in training."""
    if meta["library"] == "rsl_rl":
        from embodichain_rl import train_rsl_rl

        rsl = train_rsl_rl.play_env(meta["task"], meta, seed, video=video, num_envs=num_envs)
        policy = train_rsl_rl.load_policy(checkpoint, rsl, meta["train_cfg"])
        return rsl, lambda obs: rsl.clip(policy(rsl.to_tensordict(obs), stochastic_output=not deterministic))
    if meta["library"] == "sb3":
        from embodichain_rl import train_sb3

        sb3 = train_sb3.play_env(meta["task"], meta, seed, video=video, num_envs=num_envs)
        sb3_policy = train_sb3.load_policy(checkpoint, deterministic)
        return sb3, lambda obs: torch.as_tensor(sb3_policy(sb3.to_sb3(obs)))  # predict() clips
    raise ValueError(f"unknown library {meta['library']!r} in the run metadata (rsl_rl or sb3)")


def play(
    checkpoint: Path, video: Path, episodes: int = 1, seed: int = 0, log: Callable[[str], None] = print
) -> dict[str, Any]:
    """Run ``episodes`` episodes of the checkpoint's policy; write ``video``.

    Returns:
        ``{"returns": [...], "successes": [...], "video": path}``.
    """
    if not checkpoint.is_file():
        raise FileNotFoundError(f"no checkpoint at {checkpoint}")
    meta = read_meta(checkpoint)
    adapter, act = policy_and_env(checkpoint, meta, seed)
    env = adapter.env  # the EmbodiedEnv (both adapters keep it as .env)
    obs, _ = env.reset(seed=seed)
    frames, total = [_frame(obs)], 0.0
    returns: list[float] = []
    successes: list[bool] = []
    with torch.no_grad():
        while len(returns) < episodes:
            obs, reward, terminated, truncated, info = env.step(act(obs))
            total += float(reward[0])
            done = bool((terminated | truncated)[0])
            frames.append(_frame(info["final_obs"] if done else obs))
            if done:
                returns.append(total)
                successes.append(bool(info["final_info"]["success"][0]))
                total = 0.0
    adapter.close()
    write_mp4(frames, env.metadata.get("render_fps", 25), video)
    log(f"{episodes} episode(s): returns {[round(r, 2) for r in returns]}, success {successes}; video {video}")
    return {"returns": returns, "successes": successes, "video": str(video)}
