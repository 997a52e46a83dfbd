"""One ``embodichain generate`` run: workers, the merge and the summary.

Whatever ends the run (done, Ctrl-C, ``SIGTERM``, an error) the workers are asked to
stop, wait for their writers and close their shards within ``spec.close_timeout``
seconds, Ray is shut down (or disconnected from a cluster), and the summary is printed.
The merge runs while the workers generate (:class:`~embodichain_ray.merge.StreamingMerge`):
each batch's episodes are merged once every episode before them is, so the end of a run
waits only for the last batches' episodes and the final metadata. Every count in the summary
(merged episodes, the worker table) is what the merged dataset holds; an episode a worker had
reported but no shard holds is listed as lost. A worker that cannot start (its node lacks the
task's plugin or cannot reach the storage URI) stops the run before any episode runs, with
one message, exit 2 and no summary.
"""

from __future__ import annotations

import contextlib
import sys
import time
import traceback
from typing import Any
from collections.abc import Callable

from embodichain_ray.driver import (
    RunState,
    Scheduler,
    close_workers,
    kill_workers,
    start_workers,
)
from embodichain_ray.faults import GenerateError
from embodichain_ray.intake import Intake, PreflightError, StopFlag, await_ready
from embodichain_ray.local_ray import init_ray
from embodichain_ray.merge import StreamingMerge
from embodichain_ray.plan import GeneratePlan
from embodichain_ray.progress import progress
from embodichain_ray.reaper import Reaper
from embodichain_ray.shards import remove_tree, scan_shards, shard_folders
from embodichain_ray.spec import WORKER_DIR, GenerateSpec, seed_table
from embodichain_ray.storage import SHARED
from embodichain_ray.summary import print_summary

#: The exit code of a run stopped before any episode ran (a worker that cannot start).
EXIT_PREFLIGHT = 2


def generate(
    spec: GenerateSpec,
    plan: GeneratePlan,
    prog: str,
    on_start: Callable[[list], None] | None = None,
    started: float | None = None,
) -> int:
    """Run the workers, merge their shards into ``spec.output`` and print the summary.

    ``started`` (``time.perf_counter()``) is when the command started: the summary's wall
    time counts from it (config check and Ray's startup included).

    Returns:
        The exit code: 0, 1 (an error, or fewer than ``spec.episodes`` merged), 130 (Ctrl-C),
        143 (``SIGTERM``).
    """
    state = execute(spec, plan, prog, on_start, started)
    if state.code != EXIT_PREFLIGHT:
        print_summary(spec, plan, state)
    return state.code


def execute(
    spec: GenerateSpec,
    plan: GeneratePlan,
    prog: str,
    on_start: Callable[[list], None] | None = None,
    started: float | None = None,
) -> RunState:
    """:func:`generate` without the summary: the run's :class:`RunState` (its ``code`` set).

    ``on_start(actors)`` is called once the worker actors exist (the tests kill one from it).
    """
    from embodichain_lerobot.reading import go_offline

    go_offline()
    state = RunState(start_s=started if started is not None else time.perf_counter())
    new_shards = not spec.shards.exists()
    spec.shards.mkdir(parents=True, exist_ok=True)
    spec.stop_file.unlink(missing_ok=True)
    merge = StreamingMerge(spec.output)
    intake = Intake(spec, seed_table(spec.seed, spec.episodes, plan.max_attempts), merge)
    scan = scan_shards(spec.shards, intake.table)
    intake.resume(scan)
    if not spec.merge_only:
        state.code = _run_workers(spec, prog, plan.run.task_id, state, intake, frozenset(scan.episodes), on_start)
    if state.code == EXIT_PREFLIGHT:
        merge.abort()  # nothing half-merged is left
        if new_shards and not shard_folders(spec.shards):
            remove_tree(spec.shards)
        return state
    try:
        state.merged, state.merge_s = _finish_merge(spec, merge, state)
    except Exception as err:  # noqa: BLE001  (reported; the shards are kept with every saved episode)
        traceback.print_exception(err, file=sys.stderr)
        state.error, state.code = f"merge failed: {type(err).__name__}: {err}", 1
    if state.code == 0 and (state.failed or state.merged < spec.episodes):
        state.code = 1
    return state


def _run_workers(
    spec: GenerateSpec,
    prog: str,
    task_id: str,
    state: RunState,
    intake: Intake,
    done: frozenset,
    on_start: Callable[[list], None] | None,
) -> int:
    """Start Ray and the workers, run every episode, end the workers and Ray; the exit code so far."""
    from embodichain_core.cli.run_env import _interrupt_code

    actors: list = []
    code, scheduler, reaper = 0, None, None
    state.resumed = len(done)
    if done:
        print(f"{prog}: {len(done)} episode(s) of this run are already in {spec.shards}; running the rest")
    try:
        reaper = init_ray(spec)
        flag = start_stop_flag() if spec.transport != SHARED else None
        actors = start_workers(spec, flag)
        if on_start is not None:
            on_start(actors)
        await_ready(actors, spec)
        with progress(spec, task_id, initial=len(done)) as bar:
            scheduler = Scheduler(spec, actors, state, bar, done, take=intake.take, stop_flag=flag)
            scheduler.run()
    except KeyboardInterrupt as err:
        code, state.error = _interrupt_code(err)
        with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C this soon: the workers still close
            print(
                f"{prog}: {state.error}; the workers finish their writes and close (at most "
                f"{spec.close_timeout:.0f} s), then the saved episodes are merged",
                file=sys.stderr,
            )
    except PreflightError as err:  # no episode ran: one line, no summary
        print(f"{prog}: {err}", file=sys.stderr)
        state.error, code = str(err), EXIT_PREFLIGHT
    except GenerateError as err:  # understood: one line, no traceback
        print(f"{prog}: {err}", file=sys.stderr)
        state.error, code = str(err), 1
    except Exception as err:  # noqa: BLE001  (reported with its traceback; the saved episodes are merged)
        traceback.print_exception(err, file=sys.stderr)
        state.error, code = f"{type(err).__name__}: {err}", 1
    finally:
        state.run_s = time.perf_counter() - state.start_s
        _end_workers(spec, actors, scheduler, state)
        _shutdown(reaper)
        state.close_s = time.perf_counter() - state.start_s - state.run_s
    return code


def start_stop_flag() -> Any:
    """The :class:`StopFlag` actor, on the driver's own node: the workers take a flag they
    cannot reach for a driver that is gone and stop, so it must not live on a worker node a
    run can lose (its loss would stop every other worker, their episodes unrun)."""
    import ray
    from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

    here = NodeAffinitySchedulingStrategy(node_id=ray.get_runtime_context().get_node_id(), soft=False)
    return ray.remote(num_cpus=0)(StopFlag).options(scheduling_strategy=here).remote()


def _shutdown(reaper: Reaper | None) -> None:
    """Shut Ray down; a Ctrl-C meanwhile leaves what is left of it to the watchdog, and the
    merge and the summary still follow."""
    import ray

    try:
        ray.shutdown()
    except KeyboardInterrupt:
        print("interrupted again: the watchdog ends what is left of Ray", file=sys.stderr)
    finally:
        if reaper is not None:
            reaper.stop()


def _end_workers(spec: GenerateSpec, actors: list, scheduler: Scheduler | None, state: RunState) -> None:
    """Stop the workers (their in-flight batches return once durable), let them close their
    shards, then kill them; within ``spec.close_timeout`` s (a second Ctrl-C kills them at once)."""
    deadline = time.perf_counter() + spec.close_timeout
    try:
        if scheduler is not None and scheduler.inflight:
            scheduler.stop(spec.close_timeout)
        close_workers(actors, deadline - time.perf_counter(), state)
    except KeyboardInterrupt:
        print("second interrupt: killing the workers (their saved episodes are merged)", file=sys.stderr)
        kill_workers(actors)
    finally:
        spec.stop_file.unlink(missing_ok=True)


def _finish_merge(spec: GenerateSpec, merge: StreamingMerge, state: RunState) -> tuple[int, float]:
    """Merge what is left and move the dataset into place (Ctrl-C meanwhile is held back until
    it is done); the merged count and the seconds it took."""
    from embodichain_lerobot.writer import deferred_sigint

    started = time.perf_counter()
    with deferred_sigint():
        merged = merge.finish()
    _true_counts(state, merge.merged)
    if not merged:
        state.error = state.error or "no episode was saved"
        return 0, 0.0
    if not spec.keep_shards and merged == spec.episodes:
        remove_tree(spec.shards)
    return merged, time.perf_counter() - started


def _true_counts(state: RunState, ordered: list) -> None:
    """Set the worker table's episodes and the saved set from what the shards hold; an
    episode a worker reported that no shard holds is listed in ``state.lost``."""
    held = {ep.episode for ep in ordered}
    state.lost = sorted(set(state.saved) - held)
    state.saved = held
    for w, stats in enumerate(state.workers):
        stats.episodes = sum(ep.root.parent.name == WORKER_DIR.format(w) for ep in ordered)
