"""One generation worker: an env of ``K`` parallel envs that records given episodes.

:class:`EpisodeWorker` is plain Python (the tests drive it without Ray); the driver
wraps it in a Ray actor. It builds its env once; :meth:`EpisodeWorker.run` records a
batch of episode indices, each env slot replaying the scripted demo of one episode
seeded by :func:`~embodichain_ray.spec.episode_seed`. A failed demo is retried in a
later round with the next attempt's seed, up to ``demo_max_attempts`` attempts.

A round resets every slot with its episode seed (``save_data=False``: whatever the slot
held is dropped), replays the demo until every busy slot's episode has ended, then
commits the busy slots that are still running with a ``reset`` (the env commits the
successful ones, or all with ``save_failed_episodes``); a slot whose episode ended
early was committed by the env's auto-reset. Idle slots run an episode with a padding
seed that is never merged.

An episode is reported as saved only once it is durable: :meth:`EpisodeWorker.run` returns
after the recorder has published every committed episode (an ``AsyncLeRobotRecorder``'s
writer process is waited for, :meth:`EpisodeWorker.wait_durable`), so an episode reported
as saved survives the worker and its writer process being killed. When the driver's stop
file exists (Ctrl-C, ``SIGTERM``) the current round is abandoned after its current step
(its episodes are not committed) and ``run`` returns what earlier rounds saved.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

from embodichain_ray.spec import GenerateSpec, episode_seed, padding_seed


@dataclass
class EpisodeOutcome:
    """What became of one episode: saved (at which attempt) or failed every attempt."""

    episode: int
    attempts: int
    saved: bool


@dataclass
class BatchResult:
    """The outcome of :meth:`EpisodeWorker.run`.

    Attributes:
        outcomes: one per episode of the batch.
        env_steps: env steps taken (slots x steps, idle slots included).
        failed_attempts: demo attempts that failed (retried or not).
        seconds: wall time of the batch.
        pid: the worker's process id.
    """

    outcomes: list = field(default_factory=list)
    env_steps: int = 0
    failed_attempts: int = 0
    seconds: float = 0.0
    pid: int = 0


def _flags(value: Any, n: int) -> Any:
    import torch

    return torch.as_tensor(value, dtype=torch.bool).reshape(-1).expand(n)


class EpisodeWorker:
    """Builds worker ``worker``'s env (recording into its own shard folder) once.

    Args:
        spec: the run.
        worker: this worker's index (names its shard folder).

    Raises:
        ConfigError: the config is invalid (checked by the driver before, so unexpected here).
    """

    def __init__(self, spec: GenerateSpec, worker: int):
        from embodichain_core.cli.run_env import make_env
        from embodichain_ray.plan import load_plan

        os.environ.setdefault("SVT_LOG", "1")
        self.spec, self.worker = spec, worker
        self.plan = load_plan(spec, worker)
        self.env = make_env(self.plan.run)
        self.base = self.env.unwrapped
        self.num_envs = int(self.base.num_envs)
        self._closed = False
        self._stopped = False

    def pid(self) -> int:
        """This worker's process id (the tests kill it)."""
        return os.getpid()

    def run(self, episodes: list[int]) -> BatchResult:
        """Record ``episodes`` (each at most ``demo_max_attempts`` attempts)."""
        started = time.perf_counter()
        result = BatchResult(pid=os.getpid())
        pending = [(k, 0) for k in episodes]  # (episode, attempt), in order
        while pending and not self.stopping():
            slots, pending = pending[: self.num_envs], pending[self.num_envs :]
            success = self._round(slots, result)
            if success is None:  # stopped mid-round: nothing of it was committed
                break
            retry = []
            for (k, a), ok in zip(slots, success):
                if ok or self.plan.keep_failed:
                    result.outcomes.append(EpisodeOutcome(k, a + 1, True))
                    continue
                result.failed_attempts += 1
                if a + 1 < self.plan.max_attempts:
                    retry.append((k, a + 1))
                else:
                    result.outcomes.append(EpisodeOutcome(k, a + 1, False))
            pending = retry + pending
        self.wait_durable()
        result.seconds = time.perf_counter() - started
        return result

    def stopping(self) -> bool:
        """Whether the driver asked the workers to stop (its stop file exists)."""
        self._stopped = self._stopped or self.spec.stop_file.exists()
        return self._stopped

    def wait_durable(self) -> None:
        """Block until every committed episode is published by its recorder (a no-op for the
        synchronous recorder; an ``AsyncLeRobotRecorder`` waits for its writer process).

        Raises:
            Exception: a write failed (the recorder's own error, e.g. ``DiskFullError``).
        """
        manager = getattr(self.base, "dataset_manager", None)
        for entry in getattr(manager, "entries", {}).values():
            wait = getattr(entry.func, "wait", None)
            if callable(wait):
                wait()

    def _round(self, slots: list[tuple[int, int]], result: BatchResult) -> list[bool] | None:
        """One demo per slot; the busy slots' success (their episodes are committed), or
        ``None`` when a stop interrupted it (nothing committed)."""
        import torch

        n, busy = self.num_envs, len(slots)
        seeds = [episode_seed(self.spec.seed, k, a) for k, a in slots]
        seeds += [padding_seed(self.spec.seed, i) for i in range(busy, n)]
        self.env.reset(options={"reset_ids": list(range(n)), "episode_seeds": seeds, "save_data": False})
        replayed = self._replay(busy, result)
        if replayed is None:
            return None
        success, ended = replayed
        running = torch.nonzero(~ended[:busy]).flatten()
        if len(running):  # the commit boundary of the busy slots still running
            self.env.reset(options={"reset_ids": running})
        return [bool(s) for s in success[:busy]]

    def _replay(self, busy: int, result: BatchResult) -> tuple[Any, Any] | None:
        """Step the demo until the busy slots' episodes have all ended; per-slot success and
        ended (``None``: stopped, the round's episodes are dropped uncommitted)."""
        import torch

        n = self.num_envs
        success = torch.zeros(n, dtype=torch.bool)
        ended = torch.zeros(n, dtype=torch.bool)
        for action in self.base.create_demo_action_list() or []:
            if self.stopping():
                self._drop_live()
                return None
            _, _, terminated, truncated, info = self.env.step(torch.as_tensor(action))
            result.env_steps += n
            done = (_flags(terminated, n) | _flags(truncated, n)) & ~ended
            success |= done & _flags(info["success"], n)
            ended |= done
            if ended[:busy].all():
                return success, ended
        success |= ~ended & _flags(self.base.is_task_success(), n)
        return success, ended

    def _drop_live(self) -> None:
        """Discard the live episodes of every slot (a stop ends the round without commits)."""
        manager = getattr(self.base, "dataset_manager", None)
        for entry in getattr(manager, "entries", {}).values():
            discard = getattr(entry.func, "discard", None)
            if callable(discard):
                discard(list(range(self.num_envs)))

    def close(self) -> str | None:
        """Close the env (the recorder finalizes its shard); the shard folder or ``None``; idempotent."""
        if self._closed:
            return None
        self._closed = True
        manager = getattr(self.base, "dataset_manager", None)
        self.env.close()
        paths = [p for p in (manager.finalize() if manager is not None else []) if p]
        return str(paths[0]) if paths else None
