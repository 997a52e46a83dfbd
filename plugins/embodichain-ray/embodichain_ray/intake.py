"""What the driver takes from its workers: their start reports and each batch's episodes.

Before any episode runs, :func:`await_ready` asks every worker whether its env was built:
a node without the task's plugin, or one that cannot reach the storage URI, stops the run
with one message (:class:`PreflightError`). Then :class:`Intake` takes every returned batch:
it writes the batch's files into the driver's copy of the shard
(:func:`~embodichain_ray.transport.receive`), maps the new episodes' seeds back to run
episodes and hands them to the :class:`~embodichain_ray.merge.StreamingMerge`, which merges
them while the run goes on. A batch's episodes count as saved only once this is done.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from embodichain_ray.merge import StreamingMerge
from embodichain_ray.shards import ShardEpisode, ShardScan
from embodichain_ray.spec import GenerateSpec
from embodichain_ray.transport import receive


class StopFlag:
    """The driver's request to stop (Ctrl-C, ``SIGTERM``) where workers share no folder with
    it: a Ray actor without a CPU that the workers read."""

    def __init__(self) -> None:
        self.value = False

    def set(self) -> None:
        """Ask the workers to stop."""
        self.value = True

    def is_set(self) -> bool:
        """Whether the driver asked the workers to stop."""
        return self.value


class PreflightError(RuntimeError):
    """A worker cannot start (its node lacks a plugin, cannot reach storage): no episode ran."""


def await_ready(actors: list, spec: GenerateSpec, timeout: float = 900.0) -> None:
    """Wait until every worker has built its env (at most ``timeout`` seconds).

    Raises:
        PreflightError: a worker could not build its env or reach the storage URI; the
            message names the worker, its node and the reason.
    """
    import ray
    from ray.exceptions import RayActorError

    refs = {actor.ready.remote(): w for w, actor in enumerate(actors)}
    pending, deadline, reports = list(refs), time.monotonic() + timeout, {}
    while pending and time.monotonic() < deadline:  # short waits: a Ctrl-C is taken at once
        done, pending = ray.wait(pending, num_returns=len(pending), timeout=1.0)
        for ref in done:
            try:
                reports[refs[ref]] = ray.get(ref)
            except RayActorError:  # died while starting: Ray restarts it, the scheduler reports it
                continue
    failed = sorted((w, r) for w, r in reports.items() if r.get("error"))
    if failed:
        w, report = failed[0]
        where = report.get("node") or report.get("host") or "?"
        others = f" ({len(failed) - 1} other worker(s) too)" if len(failed) > 1 else ""
        hint = "every node needs the driver's checkout, virtual environment and plugins" + (
            "" if spec.transport in ("shared", "ray") else f", and access to --transport {spec.transport}"
        )
        raise PreflightError(
            f"worker {w} cannot start on node {where} (pid {report.get('pid')}){others}: {report['error']}; {hint}"
        )


class Intake:
    """Takes each batch's delivery into the driver's shards and the streaming merge.

    Args:
        spec: the run.
        table: the run's seed table (:func:`~embodichain_ray.spec.seed_table`).
        merge: where the episodes go.
    """

    def __init__(self, spec: GenerateSpec, table: dict[int, tuple[int, int]], merge: StreamingMerge):
        self.spec, self.table, self.merge = spec, table, merge
        self.unknown = 0

    def resume(self, scan: ShardScan) -> None:
        """Hand the episodes already in the shards (a resumed run) to the merge, in order."""
        for k in sorted(scan.episodes):
            self.merge.add(scan.episodes[k])

    def take(self, result: Any) -> None:
        """Write a batch's files into the driver's shard copy and merge its episodes.

        Raises:
            TransferLost: a file could not be fetched (its worker died first).
        """
        delivery = result.delivery
        if delivery is not None:
            root = receive(delivery, self.spec.shards, self.spec.transport)
            for rec in delivery.records:
                self._add(root, rec)
        for outcome in result.outcomes:
            if not outcome.saved:
                self.merge.skip(outcome.episode)

    def _add(self, root: Path, rec: dict) -> None:
        seed = rec.get("episode_seed")
        where = self.table.get(int(seed)) if isinstance(seed, int) else None
        if where is None:  # an idle slot's episode: never merged
            self.unknown += 1
            return
        self.merge.add(ShardEpisode(root, int(rec["lerobot_episode_index"]), where[0], where[1], rec))
