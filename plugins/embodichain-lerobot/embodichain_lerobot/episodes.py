"""Per-env episode buffers and the LeRobot frames of a finished episode.

Frame ``t`` of an episode holds the observation the policy saw (``obs_t``, the
reset observation for ``t = 0``), the action it took, and the reward and flags
of that step (``next.*``, ``annotation.*``). Observations are stored once per
step as batch snapshots shared by every env's buffer (a frame refers to row
``env_id`` of its snapshot), so recording N envs copies each observation once.

Example:
    >>> buffers = EpisodeBuffers(num_envs=2)
    >>> buffers.start(snapshot0, [0, 1])                    # after a reset  # doctest: +SKIP
    >>> buffers.add(snapshot1, StepData(action, reward, ...))  # after a step  # doctest: +SKIP
    >>> episode = buffers.take(0)                           # commit env 0  # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator, Optional

import numpy as np

Snapshot = dict  # feature name -> (N, ...) array


@dataclass(frozen=True)
class StepData:
    """One env step for every env: ``(N, ...)`` arrays."""

    action: np.ndarray
    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    success: np.ndarray


@dataclass
class Episode:
    """A finished episode of env ``env_id``: its (observation, step) pairs.

    ``seed`` is the env's episode seed (``env.episode_seeds[env_id]`` at commit
    time), ``None`` when the env does not expose one.
    """

    env_id: int
    steps: list = field(default_factory=list)
    seed: Optional[int] = None

    def __len__(self) -> int:
        return len(self.steps)

    def nbytes(self) -> int:
        """Raw size of the episode's frames (its observation rows and step values)."""
        row = self.env_id
        return sum(
            sum(arr[row].nbytes for arr in snap.values()) + step.action[row].nbytes + 16 for snap, step in self.steps
        )

    @property
    def success(self) -> bool:
        """Whether the last step reported success."""
        return bool(self.steps and self.steps[-1][1].success[self.env_id])

    def frames(self, task: str, subtask_index: int = 0) -> Iterator[dict]:
        """LeRobot frames (``add_frame`` dicts) of the episode."""
        row, last = self.env_id, len(self.steps) - 1
        for t, (snap, step) in enumerate(self.steps):
            frame: dict[str, Any] = {name: arr[row] for name, arr in snap.items()}
            frame["action"] = step.action[row]
            frame["next.reward"] = np.array([step.reward[row]], dtype=np.float32)
            frame["next.done"] = np.array([bool(step.terminated[row] or step.truncated[row])])
            frame["next.success"] = np.array([bool(step.success[row])])
            frame["subtask_index"] = np.array([subtask_index], dtype=np.int64)
            frame.update(_annotations(t, last, step, row))
            frame["task"] = task
            yield frame


def _annotations(t: int, last: int, step: StepData, row: int) -> dict[str, np.ndarray]:
    values = {
        "episode_step": t,
        "segment_id": 0,
        "segment_step": t,
        "segment_start": t == 0,
        "segment_end": t == last,
        "terminated": bool(step.terminated[row]),
        "truncated": bool(step.truncated[row]),
    }
    return {f"annotation.{k}": np.array([int(v)], dtype=np.int64) for k, v in values.items()}


class EpisodeBuffers:
    """The frames of every env's live episode."""

    def __init__(self, num_envs: int):
        self.num_envs = num_envs
        self._pending: list[Optional[Snapshot]] = [None] * num_envs
        self._steps: list[list] = [[] for _ in range(num_envs)]
        self.skipped_steps = 0

    def start(self, snapshot: Snapshot, env_ids: Iterable[int]) -> None:
        """New episodes of ``env_ids`` start from ``snapshot`` (any frames left are dropped)."""
        for i in env_ids:
            self._steps[i] = []
            self._pending[i] = snapshot

    def add(self, next_snapshot: Snapshot, step: StepData) -> None:
        """Record one step of every env; ``next_snapshot`` is the observation it returned."""
        for i in range(self.num_envs):
            if self._pending[i] is None:  # stepped before its first reset: no obs_t
                self.skipped_steps += 1
            else:
                self._steps[i].append((self._pending[i], step))
            self._pending[i] = next_snapshot

    def pending_groups(self) -> list[tuple[Snapshot, list[int]]]:
        """The observations the envs acted on this step: ``(snapshot, env_ids)`` per distinct snapshot."""
        groups: dict[int, tuple[Snapshot, list[int]]] = {}
        for i, snap in enumerate(self._pending):
            if snap is not None:
                groups.setdefault(id(snap), (snap, []))[1].append(i)
        return list(groups.values())

    def length(self, env_id: int) -> int:
        return len(self._steps[env_id])

    def take(self, env_id: int) -> Episode:
        """Remove and return env ``env_id``'s episode so far."""
        episode = Episode(env_id, self._steps[env_id])
        self._steps[env_id] = []
        return episode

    def drop(self, env_ids: Iterable[int]) -> int:
        """Drop the frames of ``env_ids``; return how many were dropped."""
        dropped = 0
        for i in env_ids:
            dropped += len(self._steps[i])
            self._steps[i] = []
        return dropped
