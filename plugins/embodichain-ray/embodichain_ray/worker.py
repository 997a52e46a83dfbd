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
as saved survives the worker and its writer process being killed. Then the batch's
:class:`~embodichain_ray.transport.Delivery` (the shard's new episodes and, without a shared
folder, their files: :mod:`embodichain_ray.transport`) goes back with it. When the driver's stop
file exists (Ctrl-C, ``SIGTERM``) the current round is abandoned after its current step
(its episodes are not committed) and ``run`` returns what earlier rounds saved.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

from embodichain_ray.spec import GenerateSpec, episode_seed, padding_seed
from embodichain_ray.transport import Delivery, ShardSender


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
        delivery: the episodes the shard gained (``None``: none yet).
    """

    outcomes: list = field(default_factory=list)
    env_steps: int = 0
    failed_attempts: int = 0
    seconds: float = 0.0
    pid: int = 0
    delivery: Delivery | None = None


def _flags(value: Any, n: int) -> Any:
    import torch

    return torch.as_tensor(value, dtype=torch.bool).reshape(-1).expand(n)


class EpisodeWorker:
    """Builds worker ``worker``'s env (recording into its own shard folder) once.

    Args:
        spec: the run.
        worker: this worker's index (names its shard folder).

    A first start that fails (a plugin missing on this node, storage it cannot reach) is
    kept for :meth:`ready`, so the driver can stop the run before any episode runs; a
    restart that fails raises (Ray then counts it as a death).

    Raises:
        Exception: a restart failed to build the env.
    """

    def __init__(self, spec: GenerateSpec, worker: int, stop_flag: Any = None):
        os.environ.setdefault("SVT_LOG", "1")
        self.spec, self.worker, self.stop_flag = spec, worker, stop_flag
        self._closed, self._stopped, self._checked = False, False, 0.0
        self.error: str | None = None
        try:
            self._build()
        except Exception as err:  # noqa: BLE001  (reported by ready() on the first start)
            if _restarted():
                raise
            self.error, self._closed = f"{type(err).__name__}: {err}", True

    def _build(self) -> None:
        from embodichain_core.cli.run_env import make_env
        from embodichain_ray.plan import load_plan
        from embodichain_ray.storage import SHARED, RAY, probe_storage

        if self.spec.transport not in (SHARED, RAY):
            probe_storage(self.spec.transport)
        self.sender = ShardSender(self.spec, self.worker)
        self.plan = load_plan(self.spec, self.sender.save_path)
        self.env = make_env(self.plan.run)
        self.base = self.env.unwrapped
        self.num_envs = int(self.base.num_envs)

    def ready(self) -> dict:
        """Where this worker runs and whether its env was built (``error``: why not)."""
        import socket

        return {"pid": os.getpid(), "host": socket.gethostname(), "node": _node_ip(), "error": self.error}

    def pid(self) -> int:
        """This worker's process id (the tests kill it)."""
        return os.getpid()

    def node_id(self) -> str:
        """The Ray node this worker runs on (the tests remove it)."""
        import ray

        return str(ray.get_runtime_context().get_node_id())

    def run(self, episodes: list[int]) -> BatchResult:
        """Record ``episodes`` (each at most ``demo_max_attempts`` attempts).

        Raises:
            RuntimeError: the env could not be built (see :meth:`ready`).
        """
        if self.error is not None:
            raise RuntimeError(self.error)
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
        result.delivery = self.sender.collect(self._shard_root())
        result.seconds = time.perf_counter() - started
        return result

    def _shard_root(self) -> Any:
        manager = getattr(self.base, "dataset_manager", None)
        for entry in getattr(manager, "entries", {}).values():
            path = getattr(entry.func, "dataset_path", None)
            if path is not None:
                return path
        return None

    def stopping(self) -> bool:
        """Whether the driver asked the workers to stop: its stop file exists (a shared folder)
        or its stop flag is set (read at most twice a second; a flag that is gone, with its
        driver, means stop)."""
        if self._stopped:
            return True
        if self.stop_flag is None:
            self._stopped = self.spec.stop_file.exists()
        elif time.monotonic() - self._checked > 0.5:
            import ray

            self._checked = time.monotonic()
            try:
                self._stopped = bool(ray.get(self.stop_flag.is_set.remote(), timeout=10))
            except Exception:  # noqa: BLE001  (the flag died with the driver)
                self._stopped = True
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
        self.sender.discard()
        return str(paths[0]) if paths else None


def _restarted() -> bool:
    """Whether this actor is a restart (Ray re-ran its constructor after a death)."""
    try:
        import ray

        return bool(ray.is_initialized() and ray.get_runtime_context().was_current_actor_reconstructed)
    except Exception:  # noqa: BLE001  (not in a Ray actor)
        return False


def _node_ip() -> str:
    try:
        import ray

        return str(ray.util.get_node_ip_address()) if ray.is_initialized() else ""
    except Exception:  # noqa: BLE001  (not in a Ray actor)
        return ""
