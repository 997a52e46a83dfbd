"""One ``embodichain generate`` run: workers, the merge and the summary.

Whatever ends the run (done, Ctrl-C, an error) the workers are ended, Ray is shut
down (or disconnected from a cluster), every episode the shards hold is merged in
episode order, and the summary is printed.
"""

from __future__ import annotations

import sys
import time
import traceback
from collections.abc import Callable

from embodichain_ray.driver import (
    RunState,
    Scheduler,
    close_workers,
    init_ray,
    kill_workers,
    start_workers,
)
from embodichain_ray.plan import GeneratePlan
from embodichain_ray.spec import GenerateSpec, seed_table


def generate(spec: GenerateSpec, plan: GeneratePlan, prog: str, on_start: Callable[[list], None] | None = None) -> int:
    """Run the workers, merge their shards into ``spec.output`` and print the summary.

    Returns:
        The exit code: 0, 1 (an error, or fewer than ``spec.episodes`` merged), 130 (Ctrl-C).
    """
    state = execute(spec, plan, prog, on_start)
    print_summary(spec, plan, state)
    return state.code


def execute(
    spec: GenerateSpec, plan: GeneratePlan, prog: str, on_start: Callable[[list], None] | None = None
) -> RunState:
    """:func:`generate` without the summary: the run's :class:`RunState` (its ``code`` set).

    ``on_start(actors)`` is called once the worker actors exist (the tests kill one from it).
    """
    from embodichain_lerobot.reading import go_offline

    go_offline()
    state = RunState(start_s=time.perf_counter())
    spec.shards.mkdir(parents=True, exist_ok=True)
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
    import ray
    from tqdm import tqdm

    actors: list = []
    code = 0
    try:
        init_ray(spec)
        actors = start_workers(spec)
        if on_start is not None:
            on_start(actors)
        with tqdm(total=spec.episodes, unit="ep", desc=plan.run.task_id, disable=not spec.show_bar) as bar:
            Scheduler(spec, actors, state, bar).run()
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; ending the workers and merging the saved episodes", file=sys.stderr)
        state.error, code = "interrupted (Ctrl-C)", 130
    except Exception as err:  # noqa: BLE001  (reported with its traceback; the saved episodes are merged)
        traceback.print_exception(err, file=sys.stderr)
        state.error, code = f"{type(err).__name__}: {err}", 1
    finally:
        state.run_s = time.perf_counter() - state.start_s
        if code == 0:
            close_workers(actors)
        else:
            kill_workers(actors)
        ray.shutdown()
    return code


def _merge(spec: GenerateSpec, plan: GeneratePlan, state: RunState) -> tuple[int, float]:
    """Merge what the shards hold (Ctrl-C during the merge is held back until it is done)."""
    from embodichain_lerobot.writer import deferred_sigint

    from embodichain_ray.merge import merge_episodes
    from embodichain_ray.shards import remove_tree, scan_shards

    started = time.perf_counter()
    scan = scan_shards(spec.shards, seed_table(spec.seed, spec.episodes, plan.max_attempts))
    ordered = [scan.episodes[k] for k in sorted(scan.episodes)]
    if not ordered:
        state.error = state.error or "no episode was saved"
        return 0, 0.0
    with deferred_sigint():
        merge_episodes(ordered, spec.output)
    if not spec.keep_shards and len(ordered) == spec.episodes:
        remove_tree(spec.shards)
    return len(ordered), time.perf_counter() - started


def print_summary(spec: GenerateSpec, plan: GeneratePlan, state: RunState) -> None:
    """``run-env``-style summary plus one line per worker."""
    merged, merge_s = state.merged, state.merge_s
    speed = state.env_steps / state.run_s if state.run_s > 0 else 0.0
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
        f"  wall time    {state.run_s + merge_s:.2f} s (workers {state.run_s:.2f} s, merge {merge_s:.2f} s)",
    ]
    if state.failed:
        shown = ", ".join(f"{k}" for k in sorted(state.failed)[:10])
        lines.append(
            f"  failed       {len(state.failed)} episode(s) failed all {plan.max_attempts} attempt(s): {shown}"
        )
    lines.append("  worker  episodes  failures  env-steps/s  restarts")
    for w, ws in enumerate(state.workers):
        lines.append(f"  {w:>6}  {ws.episodes:>8}  {ws.failures:>8}  {ws.steps_per_s:>11.1f}  {ws.restarts:>8}")
    lines.append(f"  data         {spec.output if merged else 'nothing merged'}")
    if spec.keep_shards or merged < spec.episodes:
        lines.append(f"  shards       {spec.shards}")
    if state.error:
        lines.append(f"  stopped      early: {state.error}")
    print("\n".join(lines))
