"""Replay recorded episodes in the simulator and compare them frame by frame.

:func:`replay_episode` rebuilds the dataset's env from ``meta/embodichain_env.json``
(:func:`~embodichain_lerobot.env_meta.build_env`, one env), resets it with the episode's
recorded seed, steps it with the recorded actions and compares, at every frame, the
re-simulated low-dimensional features (``observation.state`` and every other numeric
observation feature, the reward, the done and success flags) with the recorded ones,
through the recorder's own feature mapping (:class:`~embodichain_lerobot.features.FeatureSpec`).
Camera features are compared on a few frames: colour against the decoded video or
image by PSNR (lossy; over 2x2 blocks, the colour resolution of 4:2:0 video), depth and
masks (stored losslessly) exactly.

Tolerances (:func:`default_atol`): the largest absolute difference allowed for a
numeric feature is 0 (bit-exact) on the ``mujoco_batch`` backend, ``1e-3`` on ``warp``
(float32 kernels whose reductions may reorder); colour frames need a PSNR of at least
:data:`MIN_PSNR` dB. A version of the recording that differs from this process's is
reported (:func:`~embodichain_lerobot.env_meta.version_mismatches`): the replay runs,
but an exact match is only promised with the same versions.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
import torch

from embodichain_lerobot.env_meta import build_env, read_env_meta
from embodichain_lerobot.episode_reader import EpisodeFiles
from embodichain_lerobot.features import FeatureSpec, to_numpy

__all__ = ["EpisodeReplay", "MIN_PSNR", "Replayer", "default_atol", "psnr"]

#: Colour frames (lossy video) must reach this PSNR against the re-rendered frame, both
#: averaged over 2x2 blocks (:func:`psnr` with ``pool=2``). Measured on PickFork-v1, h264:
#: the right frame 34-36 dB at 320x180 and 27.7-32 dB at 64x48 and 32x24, another episode's
#: first frame 15.6 dB (320x180) and 20.8 dB (32x24). It catches a wrong scene; a frame shifted
#: by one (23-28 dB) shows in the numeric features, which are exact.
MIN_PSNR = 25.0
#: The block size colour frames are averaged over before their PSNR (4:2:0 chroma).
COLOUR_POOL = 2
#: Largest absolute error of a numeric feature, per backend (``None``: exact).
ATOL = {"mujoco_batch": 0.0, "warp": 1e-3}
#: Step outcomes compared besides the observations: feature -> key of the step.
STEP_FEATURES = ("next.reward", "next.done", "next.success")
_SKIPPED = {"action", "timestamp", "frame_index", "episode_index", "index", "task_index", "subtask_index"}
_MAP_KINDS = ("depth", "mask")


def default_atol(backend: str) -> float:
    """The numeric tolerance of a backend (exact on ``mujoco_batch``)."""
    return ATOL.get(backend, 1e-3)


def _pooled(img: np.ndarray, pool: int) -> np.ndarray:
    """``img`` (H, W, C) averaged over ``pool`` x ``pool`` blocks (edge rows/columns dropped)."""
    arr = np.asarray(img, dtype=np.float64)
    if pool <= 1:
        return arr
    h, w = arr.shape[0] // pool * pool, arr.shape[1] // pool * pool
    return arr[:h, :w].reshape(h // pool, pool, w // pool, pool, -1).mean(axis=(1, 3))


def psnr(a: np.ndarray, b: np.ndarray, pool: int = 1) -> float:
    """Peak signal-to-noise ratio of two uint8 images in dB (``inf`` when equal).

    ``pool`` > 1 compares the images averaged over ``pool`` x ``pool`` blocks: at 2, the
    resolution at which 4:2:0 video keeps colour, so chroma subsampling does not count.
    """
    mse = float(np.mean((_pooled(a, pool) - _pooled(b, pool)) ** 2))
    return float("inf") if mse == 0.0 else 10.0 * float(np.log10(255.0**2 / mse))


@dataclass
class EpisodeReplay:
    """What the replay of one episode found.

    Attributes:
        episode: the dataset's episode index.
        seed: the episode seed it was reset with.
        frames: frames compared.
        max_error: the largest absolute error of each numeric feature.
        min_psnr: the lowest PSNR (dB) of each colour feature over the sampled frames;
            depth and masks report ``inf`` when exact, else their frame's PSNR.
        failures: ``{"feature", "frame", "error"}`` of the first frame past tolerance, per feature.
    """

    episode: int
    seed: Optional[int]
    frames: int
    max_error: dict[str, float] = field(default_factory=dict)
    min_psnr: dict[str, float] = field(default_factory=dict)
    failures: list[dict[str, Any]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Every feature within tolerance."""
        return not self.failures

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (``inf`` PSNR as ``null``)."""
        out = asdict(self)
        out["min_psnr"] = {k: (None if np.isinf(v) else v) for k, v in self.min_psnr.items()}
        out["ok"] = self.ok
        return out


def _sample(length: int, count: int) -> list[int]:
    """``count`` frame indices spread over an episode (first and last included)."""
    if count <= 0 or length <= 0:
        return []
    return sorted({int(round(x)) for x in np.linspace(0, length - 1, min(count, length))})


class _Compare:
    """Per-feature running errors of one episode."""

    def __init__(self, result: EpisodeReplay, atol: float, min_psnr: float):
        self.result, self.atol, self.min_db = result, atol, min_psnr
        self._failed: set[str] = set()

    def _fail(self, name: str, frame: int, error: float) -> None:
        if name not in self._failed:
            self._failed.add(name)
            self.result.failures.append({"feature": name, "frame": frame, "error": error})

    def numeric(self, name: str, frame: int, replayed: Any, recorded: Any) -> None:
        a, b = np.asarray(replayed, dtype=np.float64).ravel(), np.asarray(recorded, dtype=np.float64).ravel()
        err = float(np.max(np.abs(a - b))) if a.size == b.size else float("inf")
        if not np.isfinite(err) and np.array_equal(a, b, equal_nan=True):
            err = 0.0
        self.result.max_error[name] = max(self.result.max_error.get(name, 0.0), err)
        if not err <= self.atol:
            self._fail(name, frame, err)

    def image(self, name: str, frame: int, replayed: np.ndarray, recorded: np.ndarray, exact: bool) -> None:
        pool = 1 if exact else COLOUR_POOL
        db = psnr(replayed, recorded, pool) if replayed.shape == recorded.shape else 0.0
        self.result.min_psnr[name] = min(self.result.min_psnr.get(name, float("inf")), db)
        if (exact and not np.isinf(db)) or db < self.min_db:
            self._fail(name, frame, db)


class Replayer:
    """Replays the episodes of one dataset in one rebuilt env.

    Args:
        root: the dataset folder.
        atol: numeric tolerance (default: :func:`default_atol` of the recorded backend).
        min_psnr: the lowest PSNR accepted for a colour frame.
        image_frames: camera frames compared per episode (0: none).
    """

    def __init__(
        self, root: str | Path, atol: Optional[float] = None, min_psnr: float = MIN_PSNR, image_frames: int = 3
    ):
        self.root = Path(root)
        self.meta = read_env_meta(self.root)
        self.atol = default_atol(str(self.meta.get("backend"))) if atol is None else float(atol)
        self.min_psnr, self.image_frames = float(min_psnr), int(image_frames)
        self.recorder_params = _recorder_params(self.meta)
        self._env: Any = None
        self._spec: Optional[FeatureSpec] = None

    @property
    def env(self) -> Any:
        """The rebuilt env (one env, recording off), built on first use."""
        if self._env is None:
            self._env = build_env(self.meta, num_envs=1)
        return self._env

    def close(self) -> None:
        """Close the rebuilt env."""
        if self._env is not None:
            self._env.close()
            self._env = None

    def replay(self, episode: int, seed: Optional[int]) -> EpisodeReplay:
        """Replay episode ``episode`` from ``seed`` (its recorded ``episode_seed``)."""
        if seed is None:
            raise ValueError(f"episode {episode} has no recorded episode_seed: it cannot be replayed")
        files = EpisodeFiles(self.root, episode)
        env = self.env.unwrapped
        obs, _ = env.reset(options={"episode_seeds": [int(seed)]})
        spec = self._feature_spec(obs, files.features)
        numeric = [s.name for s in spec.sources if s.kind == "numeric" and s.name in files.features]
        _check_features(files.features, numeric)
        recorded = {n: files.series(n) for n in [*numeric, *STEP_FEATURES, "action"]}
        sampled = _sample(files.length, self.image_frames)
        cams = [s for s in spec.sources if s.kind != "numeric" and s.name in files.features]
        result = EpisodeReplay(episode, int(seed), files.length)
        check, shots = _Compare(result, self.atol, self.min_psnr), {}
        for t in range(files.length):
            snap = spec.snapshot(obs)
            for name in numeric:
                check.numeric(name, t, snap[name][0], recorded[name][t])
            if t in sampled:
                shots[t] = {s.name: snap[s.name][0] for s in cams}
            obs, outcome = _step(env, recorded["action"][t])
            for name in STEP_FEATURES:
                check.numeric(name, t, outcome[name], recorded[name][t])
        for s in cams if sampled else ():
            frames = files.camera_frames(s.name, sampled)
            for t, frame in zip(sampled, frames):
                check.image(s.name, t, shots[t][s.name], np.asarray(frame), exact=s.kind in _MAP_KINDS)
        return result

    def _feature_spec(self, obs: Any, features: dict[str, dict]) -> FeatureSpec:
        if self._spec is None:
            self._spec = FeatureSpec(obs, self.env.unwrapped, _depth_format(features), **self.recorder_params)
        return self._spec


def _recorder_params(meta: dict[str, Any]) -> dict[str, Any]:
    """The feature-mapping params of the recording's LeRobot recorder (``environment_state``)."""
    from embodichain_lerobot.env_state import state_keys_of

    return {"environment_state": state_keys_of(meta.get("env_cfg", {}).get("dataset"))}


def _depth_format(features: dict[str, dict]) -> str:
    """How the recording stored depth and masks, from its features."""
    for name, ft in features.items():
        if name.startswith(("observation.depth.", "observation.mask.")):
            return {"video": "video", "image": "png16"}.get(ft["dtype"], "raw")
    return "png16"


def _check_features(features: dict[str, dict], replayed: Sequence[str]) -> None:
    """Every recorded numeric observation feature is re-simulated."""
    recorded = {
        n
        for n, ft in features.items()
        if ft["dtype"] not in ("video", "image")
        and n not in _SKIPPED
        and n not in STEP_FEATURES
        and not n.startswith("annotation.")
    }
    missing = sorted(recorded - set(replayed))
    if missing:
        raise ValueError(f"the rebuilt env does not produce the recorded feature(s) {missing}")


def _step(env: Any, action: np.ndarray) -> tuple[Any, dict[str, np.ndarray]]:
    """Step the one env with a recorded action: its observation and the step's recorded outcomes."""
    obs, reward, terminated, truncated, info = env.step(_action(env, action))
    first = [float(to_numpy(x).reshape(-1)[0]) for x in (reward, terminated, truncated, info.get("success", False))]
    outcome = {
        "next.reward": np.array([first[0]], dtype=np.float32),
        "next.done": np.array([float(bool(first[1] or first[2]))]),
        "next.success": np.array([float(bool(first[3]))]),
    }
    return obs, outcome


def _action(env: Any, row: np.ndarray) -> Any:
    """The recorded action row as the env's batched action (``{"qpos": ...}`` for a dict space)."""
    import gymnasium as gym

    action = torch.as_tensor(np.asarray(row, dtype=np.float32).reshape(1, -1))
    space = getattr(env, "single_action_space", None)
    if isinstance(space, gym.spaces.Dict):
        if "qpos" not in space.spaces:
            raise ValueError(f"the env's actions are a dict without 'qpos' ({list(space.spaces)}): not replayable")
        return {"qpos": action}
    return action
