"""One ``embodichain generate`` run: workers, the merge and the summary.

Whatever ends the run (done, Ctrl-C, ``SIGTERM``, an error) the workers are asked to
stop, wait for their writers and close their shards within ``spec.close_timeout``
seconds, Ray is shut down (or disconnected from a cluster), every episode the shards
hold is merged in episode order, and the summary is printed. Every count in the summary
(merged episodes, the worker table) is read from the shards, so it is what the merged
dataset holds; an episode a worker had reported but no shard holds is listed as lost.
"""

from __future__ import annotations

import contextlib
import sys
import time
import traceback
from collections.abc import Callable

from embodichain_ray.driver import (
    RunState,
    Scheduler,
    close_workers,
    kill_workers,
    start_workers,
)
from embodichain_ray.faults import GenerateError
from embodichain_ray.local_ray import init_ray
from embodichain_ray.reaper import Reaper
from embodichain_ray.plan import GeneratePlan
from embodichain_ray.progress import progress
from embodichain_ray.spec import WORKER_DIR, GenerateSpec, seed_table


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
    spec.shards.mkdir(parents=True, exist_ok=True)
    spec.stop_file.unlink(missing_ok=True)
    if not spec.merge_only:
        state.code = _run_workers(spec, plan, prog, state, on_start)
    try:
        state.merged, state.merge_s = _merge(spec, plan, state)
    except Exception as err:  # noqa: BLE001  (reported; the shards are kept with every saved episode)
        traceback.print_exception(err, file=sys.stderr)
        state.error, state.code = f"merge failed: {type(err).__name__}: {err}", 1
    if state.code == 0 and (state.failed or state.merged < spec.episodes):
        state.code = 1
    return state


def _run_workers(
    spec: GenerateSpec, plan: GeneratePlan, prog: str, state: RunState, on_start: Callable[[list], None] | None
) -> int:
    """Start Ray and the workers, run every episode, end the workers and Ray; the exit code so far."""

    from embodichain_core.cli.run_env import _interrupt_code

    actors: list = []
    code, scheduler, reaper = 0, None, None
    done = frozenset(_durable(spec, plan))
    state.resumed = len(done)
    if done:
        print(f"{prog}: {len(done)} episode(s) of this run are already in {spec.shards}; running the rest")
    try:
        reaper = init_ray(spec)
        actors = start_workers(spec)
        if on_start is not None:
            on_start(actors)
        with progress(spec, plan.run.task_id, initial=len(done)) as bar:
            scheduler = Scheduler(spec, actors, state, bar, done)
            scheduler.run()
    except KeyboardInterrupt as err:
        code, state.error = _interrupt_code(err)
        with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C this soon: the workers still close
            print(
                f"{prog}: {state.error}; the workers finish their writes and close (at most "
                f"{spec.close_timeout:.0f} s), then the saved episodes are merged",
                file=sys.stderr,
            )
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


def _durable(spec: GenerateSpec, plan: GeneratePlan) -> set:
    """The run's episodes that the shards already hold (a resumed run does not run them again)."""
    from embodichain_ray.shards import scan_shards

    return set(scan_shards(spec.shards, seed_table(spec.seed, spec.episodes, plan.max_attempts)).episodes)


def _merge(spec: GenerateSpec, plan: GeneratePlan, state: RunState) -> tuple[int, float]:
    """Merge what the shards hold (Ctrl-C during the merge is held back until it is done)."""
    from embodichain_lerobot.writer import deferred_sigint

    from embodichain_ray.merge import merge_episodes
    from embodichain_ray.shards import remove_tree, scan_shards

    started = time.perf_counter()
    scan = scan_shards(spec.shards, seed_table(spec.seed, spec.episodes, plan.max_attempts))
    ordered = [scan.episodes[k] for k in sorted(scan.episodes)]
    _true_counts(state, ordered)
    if not ordered:
        state.error = state.error or "no episode was saved"
        return 0, 0.0
    with deferred_sigint():
        merge_episodes(ordered, spec.output)
    if not spec.keep_shards and len(ordered) == spec.episodes:
        remove_tree(spec.shards)
    return len(ordered), time.perf_counter() - started


def _true_counts(state: RunState, ordered: list) -> None:
    """Set the worker table's episodes and the saved set from what the shards hold; an
    episode a worker reported that no shard holds is listed in ``state.lost``."""
    held = {ep.episode for ep in ordered}
    state.lost = sorted(set(state.saved) - held)
    state.saved = held
    for w, stats in enumerate(state.workers):
        stats.episodes = sum(ep.root.parent.name == WORKER_DIR.format(w) for ep in ordered)


def print_summary(spec: GenerateSpec, plan: GeneratePlan, state: RunState) -> None:
    """``run-env``-style summary plus one line per worker."""
    merged, merge_s = state.merged, state.merge_s
    speed = state.env_steps / state.run_s if state.run_s > 0 else 0.0
    wall = time.perf_counter() - state.start_s
    lines = [
        f"generate summary: {plan.run.task_id}",
        (
            f"  episodes     {merged}/{spec.episodes} merged ({spec.workers} worker(s) x {spec.num_envs} env(s), "
            f"seed {spec.seed})"
        ),
        (
            f"  env steps    {state.env_steps} ({speed:.1f} env-steps/s overall, {state.busy_steps_per_s:.1f} "
            "while the workers ran)"
        ),
        (
            f"  wall time    {wall:.2f} s (startup and workers {state.run_s:.2f} s, closing {state.close_s:.2f} s, "
            f"merge {merge_s:.2f} s)"
        ),
    ]
    if state.resumed:
        lines.append(f"  resumed      {state.resumed} episode(s) were already in the shards")
    if state.failed:
        shown = ", ".join(f"{k}" for k in sorted(state.failed)[:10])
        lines.append(
            f"  failed       {len(state.failed)} episode(s) failed all {plan.max_attempts} attempt(s): {shown}"
        )
    lines.append("  worker  episodes  failures  env-steps/s  restarts")
    for w, ws in enumerate(state.workers):
        note = "  (died while closing its shard)" if ws.died_closing else ""
        lines.append(f"  {w:>6}  {ws.episodes:>8}  {ws.failures:>8}  {ws.steps_per_s:>11.1f}  {ws.restarts:>8}{note}")
    lines += _missing_lines(spec, state)
    lines.append(f"  data         {spec.output if merged else 'nothing merged'}")
    if spec.keep_shards or merged < spec.episodes:
        lines.append(f"  shards       {spec.shards}")
    if state.error:
        lines.append(f"  stopped      early: {state.error}")
    print("\n".join(lines))


def _missing_lines(spec: GenerateSpec, state: RunState) -> list[str]:
    """Summary lines naming the episodes that are not in the merged dataset, and how to run them."""
    lines = []
    if state.lost:
        shown = ", ".join(str(k) for k in state.lost[:20])
        lines.append(f"  lost         {len(state.lost)} episode(s) reported saved but in no shard: {shown}")
    missing = [k for k in range(spec.episodes) if k not in state.saved and k not in state.failed]
    if missing and not spec.merge_only:
        shown = ", ".join(str(k) for k in missing[:20]) + (", ..." if len(missing) > 20 else "")
        lines.append(
            f"  not saved    {len(missing)} episode(s): {shown}; to run just these, delete the output "
            f"and run the same command again with --shards {spec.shards}"
        )
    return lines
