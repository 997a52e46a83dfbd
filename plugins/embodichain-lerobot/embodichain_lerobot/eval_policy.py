"""Evaluate a LeRobot policy in a batched env: :func:`evaluate`.

The ``num_envs`` envs step together; the policy runs on the whole batch, with one rollout
state per env (:class:`~embodichain_lerobot.policy_state.PerEnvPolicy`), so an env that
finishes its episode starts the next one at once while the others go on. An episode ends
when its env terminates or truncates (the env's ``max_episode_steps``); its success is the
env's ``success`` flag of its last step. Episodes are numbered in the order they start.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np
import torch

from embodichain_lerobot.env_state import state_keys_of, trained_state_keys
from embodichain_lerobot.policy_inputs import ObservationMapper
from embodichain_lerobot.policy_io import LoadedPolicy
from embodichain_lerobot.policy_state import PerEnvPolicy

__all__ = ["EpisodeResult", "EvalResult", "evaluate"]


@dataclass
class EpisodeResult:
    """One evaluated episode."""

    episode: int
    env_id: int
    success: bool
    episode_return: float  # the sum of the episode's rewards
    length: int
    terminated: bool
    truncated: bool
    video: Optional[str] = None
    episode_seed: Optional[int] = None  # the env's seed of the episode (compare with a dataset's)
    #: the task's metrics (``info["metrics"]``, e.g. PickFork-v1's ``fork_height``) at the last step:
    #: how far a failed episode got
    metrics: dict[str, float] = field(default_factory=dict)


@dataclass
class EvalResult:
    """What :func:`evaluate` measured."""

    episodes: list[EpisodeResult] = field(default_factory=list)
    env_steps: int = 0
    seconds: float = 0.0

    @property
    def success_rate(self) -> float:
        """Fraction of successful episodes."""
        return float(np.mean([e.success for e in self.episodes])) if self.episodes else 0.0

    @property
    def mean_return(self) -> float:
        """Mean episode return."""
        return float(np.mean([e.episode_return for e in self.episodes])) if self.episodes else 0.0

    @property
    def mean_length(self) -> float:
        """Mean episode length in steps."""
        return float(np.mean([e.length for e in self.episodes])) if self.episodes else 0.0

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary with the per-episode results."""
        return {
            "num_episodes": len(self.episodes),
            "success_rate": self.success_rate,
            "mean_return": self.mean_return,
            "mean_length": self.mean_length,
            "env_steps": self.env_steps,
            "seconds": round(self.seconds, 3),
            "episodes": [asdict(e) for e in self.episodes],
        }


class _Rollout:
    """Per-env counters of the running episodes, and their video frames."""

    def __init__(self, num_envs: int, episodes: int, video_dir: Optional[Path]):
        self.episodes, self.video_dir = episodes, video_dir
        self.index = list(range(num_envs))  # episode number each env runs (>= episodes: not counted)
        self.started = num_envs
        self.returns = np.zeros(num_envs)
        self.lengths = np.zeros(num_envs, dtype=np.int64)
        self.frames: list[list[np.ndarray]] = [[] for _ in range(num_envs)]
        self.seeds: list[Optional[int]] = [None] * num_envs  # episode seed of each env's running episode

    def read_seeds(self, env: Any, env_ids: Any) -> None:
        """Note the episode seeds of the episodes ``env_ids`` just started."""
        seeds = getattr(env, "episode_seeds", None)
        for i in env_ids:
            self.seeds[i] = int(seeds[i]) if seeds is not None else None

    def add_frames(self, frames: dict[str, np.ndarray], env_ids: Any) -> None:
        if self.video_dir is not None:
            for i in env_ids:
                if self.index[i] < self.episodes:
                    self.frames[i].append(np.concatenate([f[i] for f in frames.values()], axis=1))

    def finish(
        self, i: int, success: bool, terminated: bool, truncated: bool, fps: int, metrics: dict[str, float]
    ) -> Optional[EpisodeResult]:
        """Close env ``i``'s episode; its result when it counts. Env ``i`` starts the next one."""
        result = None
        if self.index[i] < self.episodes:
            result = EpisodeResult(
                self.index[i], i, success, float(self.returns[i]), int(self.lengths[i]), terminated, truncated
            )
            result.episode_seed, result.metrics = self.seeds[i], metrics
            if self.video_dir is not None:
                result.video = str(self._write_video(self.index[i], self.frames[i], fps))
        self.index[i], self.started = self.started, self.started + 1
        self.returns[i], self.lengths[i], self.frames[i] = 0.0, 0, []
        return result

    def _write_video(self, episode: int, frames: list[np.ndarray], fps: int) -> Path:
        from embodichain_lerobot.preview import write_mp4

        assert self.video_dir is not None
        return write_mp4({"cameras": frames}, fps, self.video_dir / f"episode_{episode:04d}.mp4")


def _env_action(env: Any, action: torch.Tensor) -> Any:
    """The policy's ``(N, A)`` action as the env takes it (``{"qpos": ...}`` for a dict space)."""
    space = env.action_space
    if hasattr(space, "spaces") and "qpos" in space.spaces:
        return {"qpos": action}
    return action


def _episode_metrics(metrics: Any, n: int) -> list[dict[str, float]]:
    """Each env's scalar task metrics (one value per env; others are left out), rounded."""
    rows: list[dict[str, float]] = [{} for _ in range(n)]
    for name, value in (metrics or {}).items():
        values = torch.as_tensor(value).detach().reshape(-1).cpu()
        if values.numel() == n and values.dtype.is_floating_point:
            for i in range(n):
                rows[i][str(name)] = round(float(values[i]), 5)
    return rows


def _check_action_dim(env: Any, loaded: LoadedPolicy) -> None:
    from embodichain_core.config.errors import ConfigError

    space = env.action_space
    space = space.spaces["qpos"] if hasattr(space, "spaces") and "qpos" in space.spaces else space
    env_dim = int(space.shape[-1]) if getattr(space, "shape", None) else None
    if env_dim is not None and env_dim != loaded.action_dim:
        raise ConfigError(
            "policy",
            f"the policy's action has {loaded.action_dim} values, the env's action {env_dim} (action space {space})",
        )


def evaluate(
    env: Any,
    loaded: LoadedPolicy,
    episodes: int,
    seed: Optional[int] = None,
    video_dir: Optional[Path] = None,
    progress: Optional[Callable[[EpisodeResult], None]] = None,
    instruction: Optional[str] = None,
) -> EvalResult:
    """Run ``episodes`` episodes of the policy in ``env`` (all its ``num_envs`` envs).

    Args:
        env: a batched embodichain env (``gym.make(task_id, ...)``), closed by the caller.
        loaded: the policy and its processors (:func:`~embodichain_lerobot.policy_io.load_policy`).
        episodes: how many episodes to evaluate.
        seed: the env's reset seed (default: the env's own seeding).
        video_dir: write ``episode_<n>.mp4`` of each episode there (the observation cameras,
            side by side).
        progress: called with each finished episode (e.g. to update a progress bar).
        instruction: the language instruction given to the policy as ``"task"``.

    Raises:
        ConfigError: ``policy``: the env's observations or action do not fit the policy.
    """
    import time

    base = env.unwrapped
    obs, _ = env.reset(seed=seed)
    # the recorder's list in the env config, else the one of the dataset the policy was trained on
    keys = state_keys_of(getattr(base.cfg, "dataset", None)) or trained_state_keys(loaded.path)
    mapper = ObservationMapper(obs, base, loaded.config, instruction, environment_state=keys)
    _check_action_dim(env, loaded)
    if video_dir is not None and not mapper.cameras:
        from embodichain_core.config.errors import ConfigError

        raise ConfigError("video", "the env's observations have no colour camera to record")
    fps = int(base.metadata.get("render_fps") or 25)
    runner = PerEnvPolicy(loaded.policy, mapper.num_envs)
    state = _Rollout(mapper.num_envs, episodes, Path(video_dir) if video_dir is not None else None)
    state.read_seeds(base, range(mapper.num_envs))
    result = EvalResult()
    started = time.perf_counter()
    while len(result.episodes) < episodes:
        obs = _step(env, obs, loaded, mapper, runner, state, result, fps, progress)
    result.episodes.sort(key=lambda e: e.episode)
    result.seconds = time.perf_counter() - started
    return result


def _step(
    env: Any,
    obs: Any,
    loaded: LoadedPolicy,
    mapper: ObservationMapper,
    runner: PerEnvPolicy,
    state: _Rollout,
    result: EvalResult,
    fps: int,
    progress: Optional[Callable] = None,
) -> Any:
    """One batched step; finished episodes go to ``result``. Returns the next observation."""
    n = mapper.num_envs
    state.add_frames(mapper.frames(obs) if state.video_dir is not None else {}, range(n))
    with torch.inference_mode():
        action = loaded.postprocessor(runner.select_action(loaded.preprocessor(mapper(obs))))
    action = action.float().reshape(n, -1).clone()  # a normal tensor: the env may change it in place
    obs, reward, terminated, truncated, info = env.step(_env_action(env, action))
    result.env_steps += n
    reward, term, trunc = (torch.as_tensor(x).reshape(n).cpu().numpy() for x in (reward, terminated, truncated))
    state.returns += reward
    state.lengths += 1
    done = np.flatnonzero(term | trunc)
    if len(done):
        final = info.get("final_info", info)
        success = torch.as_tensor(final.get("success", torch.zeros(n, dtype=torch.bool))).reshape(n).cpu().numpy()
        state.add_frames(mapper.frames(info["final_obs"]) if state.video_dir is not None else {}, done)
        metrics = _episode_metrics(final.get("metrics"), n)
        for i in done:
            episode = state.finish(int(i), bool(success[i]), bool(term[i]), bool(trunc[i]), fps, metrics[i])
            if episode is not None:
                result.episodes.append(episode)
                if progress is not None:
                    progress(episode)
        runner.reset(done)
        state.read_seeds(env.unwrapped, done)
    return obs
