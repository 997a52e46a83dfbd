"""The driver of ``embodichain generate``: Ray, the episode queue, faults and progress.

The queue of episode indices lives in the driver; each worker actor has one batch of
``K`` episodes in flight and gets the next batch as soon as it returns, so a slow
worker takes fewer episodes (dynamic load balancing). A batch whose worker died
(``SIGKILL``, out of memory) goes back to the front of the queue; Ray restarts the
actor (``max_restarts``), whose constructor builds a fresh env recording into a *new*
shard folder. Episodes that a dead batch had already published are found again in the
old shard and de-duplicated at the merge.

A worker reports a batch only once its episodes are durable (see
:mod:`embodichain_ray.worker`), so the driver's count never runs ahead of the shards. A
stop (Ctrl-C, ``SIGTERM``: :meth:`Scheduler.stop`) creates the stop file, which every worker
checks after each step: the workers drop the round they are in, wait for their writers
and return; then they close their shards (:func:`close_workers`), all within
``spec.close_timeout`` seconds, after which the ones still busy are killed (what they had
published is merged). Episodes already in the shards when a run starts are not run again
(resuming an interrupted run).
"""

from __future__ import annotations

import logging
import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from embodichain_ray.faults import PROG, GenerateError, death_reason, worker_death_note
from embodichain_ray.spec import GenerateSpec
from embodichain_ray.transport import TransferLost
from embodichain_ray.worker import BatchResult

log = logging.getLogger("embodichain_ray")
#: Once every episode is done, how long the run still waits for restarting workers (a worker
#: whose node is gone may find no CPU to restart on; the run then ends without it).
RESTART_GRACE_S = 30.0


@dataclass
class WorkerStats:
    """Per-worker counters for the summary table."""

    episodes: int = 0
    failures: int = 0
    env_steps: int = 0
    busy_s: float = 0.0
    restarts: int = 0
    pid: int = 0  # the process of its last batch
    dead: bool = False
    died_closing: bool = False

    @property
    def steps_per_s(self) -> float:
        """Env steps per second of this worker's batches."""
        return self.env_steps / self.busy_s if self.busy_s > 0 else 0.0


@dataclass
class RunState:
    """What the driver knows: saved and failed episodes, per-worker stats, timings, the outcome."""

    saved: set = field(default_factory=set)
    failed: dict = field(default_factory=dict)  # episode -> attempts
    workers: list = field(default_factory=list)
    env_steps: int = 0
    start_s: float = 0.0
    run_s: float = 0.0
    close_s: float = 0.0
    resumed: int = 0
    lost: list = field(default_factory=list)  # episodes a worker reported that no shard holds
    error: str | None = None
    merged: int = 0
    merge_s: float = 0.0
    code: int = 0

    @property
    def busy_steps_per_s(self) -> float:
        """Env steps per second while the workers ran batches (startup excluded)."""
        busy = max((w.busy_s for w in self.workers), default=0.0)
        return self.env_steps / busy if busy > 0 else 0.0


def start_workers(spec: GenerateSpec, stop_flag: Any = None) -> list:
    """One restartable actor per worker (1 CPU each); ``stop_flag``: a
    :class:`~embodichain_ray.intake.StopFlag` actor the workers read (no shared folder).

    Raises:
        GenerateError: the cluster has fewer CPUs than workers (an actor would wait forever).
    """
    import ray

    cpus = int(ray.cluster_resources().get("CPU", 0))
    if cpus < spec.workers:
        raise GenerateError(
            f"the Ray cluster has {cpus} CPU(s) for {spec.workers} worker(s) of 1 CPU each; "
            "lower --workers or add machines"
        )

    from embodichain_ray.worker import EpisodeWorker

    cls = ray.remote(num_cpus=1, max_restarts=spec.max_restarts, max_task_retries=0)(EpisodeWorker)
    return [cls.remote(spec, w, stop_flag) for w in range(spec.workers)]


class Scheduler:
    """Hands batches of episode indices to idle workers until every episode is done.

    A worker whose batch failed because its process died gets a ``pid`` probe instead
    of a batch; Ray answers it once the actor is back (restarted, counted once per
    failure), then the worker gets batches again. A worker past its
    ``max_restarts`` is dead; when every worker is dead the run stops. ``take(result)``
    takes each returned batch's episodes (:class:`~embodichain_ray.intake.Intake`) before
    they count; a batch whose files are lost (:class:`~embodichain_ray.transport.TransferLost`)
    is run again and its worker restarted (its incarnation's shard is not added to again).
    The run ends when every episode is done, even while a worker waits for a node to restart on.
    """

    def __init__(
        self,
        spec: GenerateSpec,
        actors: list,
        state: RunState,
        bar: Any,
        done: frozenset = frozenset(),
        take: Callable[[BatchResult], None] | None = None,
        stop_flag: Any = None,
    ):
        self.spec, self.actors, self.state, self.bar, self.take = spec, actors, state, bar, take
        self.stop_flag = stop_flag
        self.queue: deque = deque(k for k in range(spec.episodes) if k not in done)
        state.saved |= set(done)  # the bar starts at len(done)
        self.inflight: dict = {}  # ObjectRef -> (worker, batch); batch None: a pid probe
        self.down: list = [False] * len(actors)
        state.workers = [WorkerStats() for _ in actors]

    def _submit(self, worker: int) -> None:
        if not self.queue or self.state.workers[worker].dead:
            return
        batch = [self.queue.popleft() for _ in range(min(self.spec.num_envs, len(self.queue)))]
        self.inflight[self.actors[worker].run.remote(batch)] = (worker, batch)

    def _probe(self, worker: int) -> None:
        self.inflight[self.actors[worker].pid.remote()] = (worker, None)

    def run(self) -> None:
        """Run to the end (raises ``KeyboardInterrupt`` on Ctrl-C, :class:`GenerateError` when all workers died)."""
        import ray

        for w in range(len(self.actors)):
            self._submit(w)
        last = time.monotonic()
        while self.inflight and (self.queue or not self._only_probes() or time.monotonic() - last < RESTART_GRACE_S):
            ready, _ = ray.wait(list(self.inflight), num_returns=1, timeout=1.0)
            last = last if self._only_probes() else time.monotonic()
            for ref in ready:
                worker, batch = self.inflight.pop(ref)
                if self._collect(ref, worker, batch):
                    self._submit(worker)
                elif not self.state.workers[worker].dead:
                    self._probe(worker)
        self.inflight = {ref: v for ref, v in self.inflight.items() if v[1] is not None}  # no probe to wait for
        if self.queue:  # the loop only ends with episodes left when no worker is left
            raise GenerateError(f"every worker is gone ({self.state.error}); {len(self.queue)} episode(s) were not run")

    def _only_probes(self) -> bool:
        """Whether every call in flight is a restart probe (no batch is running)."""
        return all(batch is None for _, batch in self.inflight.values())

    def stop(self, timeout: float) -> None:
        """Ask every worker to stop (the stop file) and take the batches they return within
        ``timeout`` seconds (their episodes are durable); a second Ctrl-C is raised at once."""
        import ray

        self.spec.stop_file.touch()
        if self.stop_flag is not None:
            self.stop_flag.set.remote()
        self.queue.clear()
        deadline = time.perf_counter() + timeout
        while self.inflight and time.perf_counter() < deadline:  # a second Ctrl-C propagates: no more waiting
            left = max(deadline - time.perf_counter(), 0.0)
            ready, _ = ray.wait(list(self.inflight), num_returns=1, timeout=min(left, 1.0))
            for ref in ready:
                worker, batch = self.inflight.pop(ref)
                self._collect(ref, worker, batch, requeue=False)

    def _collect(self, ref: Any, worker: int, batch: list | None, requeue: bool = True) -> bool:
        """Take a finished call's result; ``False`` when the worker is down (its batch re-queued)."""
        import ray
        from ray.exceptions import ActorDiedError, RayActorError

        stats = self.state.workers[worker]
        try:
            value = ray.get(ref)
            if batch is not None and self.take is not None:
                self.take(value)
        except TransferLost as err:  # its worker died before the driver had the files: run it again
            if requeue:
                self.queue.extendleft(reversed(batch or []))
            print(
                f"{PROG}: worker {worker}'s episode(s) {batch} were lost in transfer ({err}); they run again",
                file=sys.stderr,
            )
            ray.kill(self.actors[worker], no_restart=False)  # a new incarnation, a new shard
            return False
        except RayActorError as err:  # the worker died (killed, out of memory): run its batch again
            if batch is not None and requeue:
                self.queue.extendleft(reversed(batch))
            if not self.down[worker]:
                self.down[worker], stats.restarts = True, stats.restarts + 1
            gone = isinstance(err, ActorDiedError) and batch is None  # past max_restarts, or it cannot start
            stats.dead = stats.dead or gone
            limit = self.spec.max_restarts
            note = worker_death_note(worker, batch, err, stats.restarts, limit, requeue, gone, stats.pid)
            if note:
                print(f"{PROG}: {note}", file=sys.stderr, flush=True)
            if gone:
                self.state.error = f"worker {worker} is gone: {death_reason(err, stats.pid)}"
            return False
        self.down[worker] = False
        if batch is not None:
            self._record(stats, value)
        else:
            stats.pid = int(value)
        return True

    def _record(self, stats: WorkerStats, result: BatchResult) -> None:
        before = len(self.state.saved)
        for outcome in result.outcomes:
            if outcome.saved:
                self.state.saved.add(outcome.episode)
            else:
                self.state.failed[outcome.episode] = outcome.attempts
        stats.episodes += len(self.state.saved) - before
        stats.pid = result.pid
        stats.failures += result.failed_attempts
        stats.env_steps += result.env_steps
        stats.busy_s += result.seconds
        self.state.env_steps += result.env_steps
        self.bar.update(len(self.state.saved) - before)
        elapsed = time.perf_counter() - self.state.start_s
        self.bar.set_postfix_str(f"{self.state.env_steps / max(elapsed, 1e-9):.1f} env-steps/s", refresh=False)


def close_workers(actors: list, timeout: float = 120.0, state: RunState | None = None) -> None:
    """Let every live worker finalize its shard (up to ``timeout`` s), then kill them all.

    A worker that dies or fails while closing is marked ``died_closing`` in ``state``: every
    episode it reported was durable before, so its shard still holds them.
    """
    import ray

    refs: dict = {}
    for worker, actor in enumerate(actors):
        try:
            refs[actor.close.remote()] = worker
        except Exception as err:  # noqa: BLE001  (an actor gone for good: its shard is as it was left)
            log.debug("worker %d cannot close: %r", worker, err)
    if refs:
        done, _ = ray.wait(list(refs), num_returns=len(refs), timeout=max(timeout, 0.0))
        for ref in done:
            try:
                ray.get(ref)
            except Exception as err:  # noqa: BLE001  (a shard that failed to finalize keeps its episodes)
                print(
                    f"{PROG}: worker {refs[ref]} died while closing its shard ({death_reason(err)}); "
                    "the episodes it saved before are in its shard and are merged",
                    file=sys.stderr,
                )
                if state is not None and state.workers:
                    state.workers[refs[ref]].died_closing = True
    kill_workers(actors)


def kill_workers(actors: list) -> None:
    """Kill the actors for good (their shards keep every published episode)."""
    import ray

    for worker, actor in enumerate(actors):
        try:
            ray.kill(actor, no_restart=True)
        except Exception as err:  # noqa: BLE001  (already gone)
            log.debug("worker %d: %r", worker, err)
