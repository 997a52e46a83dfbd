"""What passes between the env's thread and a viewer's thread.

The env thread writes a :class:`Snapshot` into a :class:`LatestSlot` (one slot: a newer
snapshot replaces one the viewer has not drawn yet, so a slow viewer drops frames and
never holds the loop back). The viewer writes the user's requests into :class:`Controls`,
which the env thread reads before each step.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

#: Speeds offered by the viewers: ``None`` runs as fast as the loop goes, a number is a
#: multiple of real time (one control step per ``step_dt / speed`` seconds at most).
SPEEDS: tuple[Optional[float], ...] = (None, 0.125, 0.25, 0.5, 1.0, 2.0, 4.0)


def speed_label(speed: Optional[float]) -> str:
    """``"max"`` or ``"0.5x"``."""
    return "max" if speed is None else f"{speed:g}x"


def next_speed(speed: Optional[float], step: int) -> Optional[float]:
    """The speed ``step`` places along :data:`SPEEDS` from ``speed`` (wrapping around); a
    speed between two of them (``--speed 0.3``) moves to its neighbour on that side."""
    if speed in SPEEDS:
        return SPEEDS[(SPEEDS.index(speed) + step) % len(SPEEDS)]
    numbers = [s for s in SPEEDS if s is not None]
    if step > 0:
        return next((s for s in numbers if s > speed), None)  # type: ignore[operator]
    return next((s for s in reversed(numbers) if s < speed), None)  # type: ignore[operator]


@dataclass
class Snapshot:
    """The state of every env after one step, and the viewed env's task readings.

    Attributes:
        step: control steps taken since the viewer opened.
        qpos: ``(num_envs, nq)`` joint positions.
        mocap_pos: ``(num_envs, nmocap, 3)`` (``nmocap`` may be 0).
        mocap_quat: ``(num_envs, nmocap, 4)`` (wxyz).
        env_idx: the env the readings below belong to.
        episode_step: that env's step in its episode.
        reward: its reward this step.
        terms: its reward terms (``info["rewards"]``).
        metrics: the task's metrics (``info["metrics"]``) that are one number per env.
        success: its ``info["success"]``.
        images: its camera images, ``"<sensor>/<key>"`` -> ``(H, W, 3)`` uint8.
    """

    step: int
    qpos: np.ndarray
    mocap_pos: np.ndarray
    mocap_quat: np.ndarray
    env_idx: int = 0
    episode_step: int = 0
    reward: float = 0.0
    terms: dict[str, float] = field(default_factory=dict)
    metrics: dict[str, float] = field(default_factory=dict)
    success: bool = False
    images: dict[str, np.ndarray] = field(default_factory=dict)


def reading_rows(snap: Snapshot) -> list[tuple[str, str]]:
    """The viewed env's readings as ``(name, value)`` rows, the same in both viewers:
    success, reward, each reward term, each metric."""
    return [
        ("success", "yes" if snap.success else "no"),
        ("reward", f"{snap.reward:.4g}"),
        *((name, f"{value:.4g}") for name, value in snap.terms.items()),
        *((name, f"{value:.4g}") for name, value in snap.metrics.items()),
    ]


class LatestSlot:
    """Holds the newest snapshot; ``get`` waits for one newer than the caller has seen."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._value: Optional[Snapshot] = None
        self._version = 0
        self._taken = 0  # the version a viewer took last
        self.dropped = 0  # snapshots replaced before a viewer took them

    def put(self, value: Snapshot) -> None:
        """Replace the held snapshot (never waits for the viewer)."""
        with self._cond:
            if self._value is not None and self._taken < self._version:
                self.dropped += 1
            self._value = value
            self._version += 1
            self._cond.notify_all()

    def get(self, seen: int, timeout: float) -> tuple[int, Optional[Snapshot]]:
        """``(version, snapshot)`` newer than ``seen``, or ``(seen, None)`` after ``timeout`` s."""
        with self._cond:
            if self._version <= seen:
                self._cond.wait(timeout)
            if self._version <= seen:
                return seen, None
            self._taken = self._version
            return self._version, self._value


@dataclass
class Controls:
    """The user's requests, written by a viewer, read by the env thread before a step.

    Attributes:
        env_idx: the env shown (and reset by ``reset``).
        paused: hold the loop before its next step.
        steps: single steps granted while paused.
        reset: reset the viewed env before the next step (its episode is not recorded).
        speed: see :data:`SPEEDS`.
        closed: the viewer is gone (its window closed): the loop is never held.
    """

    env_idx: int = 0
    paused: bool = False
    steps: int = 0
    reset: bool = False
    speed: Optional[float] = None
    closed: bool = False
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def request_step(self) -> None:
        """One more single step (pauses the loop if it runs)."""
        with self._lock:
            self.paused = True
            self.steps += 1

    def take_step(self) -> bool:
        """Whether the env thread may step now (consumes a granted single step)."""
        with self._lock:
            if self.closed or not self.paused:
                return True
            if self.steps > 0:
                self.steps -= 1
                return True
            return False

    def take_reset(self) -> bool:
        """Whether a reset was requested (clears the request)."""
        with self._lock:
            asked, self.reset = self.reset, False
            return asked


#: Where both viewers' cameras start, around the model's centre (MuJoCo's convention:
#: azimuth about +z from +x, a negative elevation looks down).
CAMERA_AZIMUTH, CAMERA_ELEVATION = 150.0, -25.0


def camera_distance(model: Any) -> float:
    """How far a viewer's camera starts from the scene: three extents, at most 2.5 m (a
    floor plane makes the model's extent far larger than a table top)."""
    return float(min(3.0 * model.stat.extent, 2.5))


def camera_pose(model: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(position, look_at)`` in world coordinates of the camera both viewers open with:
    :func:`camera_distance` from the model's centre, at :data:`CAMERA_AZIMUTH` and
    :data:`CAMERA_ELEVATION` (what MuJoCo's free camera does with those settings)."""
    look_at = np.asarray(model.stat.center, dtype=np.float64).copy()
    az, el = np.deg2rad(CAMERA_AZIMUTH), np.deg2rad(CAMERA_ELEVATION)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    return look_at - camera_distance(model) * forward, look_at


def image_rgb(value: Any) -> Optional[np.ndarray]:
    """One env's camera output as ``(H, W, 3)`` uint8: colour as it is, depth or a mask
    scaled to grey; ``None`` for what is not an image."""
    arr = np.asarray(value.detach().cpu() if hasattr(value, "detach") else value)
    if arr.ndim == 3 and arr.shape[-1] == 1:
        arr = arr[..., 0]
    if arr.ndim == 3 and arr.shape[-1] in (3, 4) and arr.dtype == np.uint8:
        return np.ascontiguousarray(arr[..., :3])
    if arr.ndim != 2 or arr.size == 0:
        return None
    finite = np.isfinite(arr)
    values = arr[finite].astype(np.float64)
    lo, hi = (float(values.min()), float(values.max())) if values.size else (0.0, 1.0)
    grey = np.zeros(arr.shape, dtype=np.uint8)
    grey[finite] = np.clip((values - lo) / (hi - lo or 1.0) * 255.0, 0, 255).astype(np.uint8)
    return np.repeat(grey[..., None], 3, axis=2)
