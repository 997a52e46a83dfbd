"""The summary of an ``embodichain generate`` run: counts read from the merged dataset.

Every count (merged episodes, the worker table) is what the merged dataset holds; an episode
a worker had reported but no shard holds is listed as lost, and the episodes not saved are
named with the command that runs just them.
"""

from __future__ import annotations

import time

from embodichain_ray.driver import RunState
from embodichain_ray.plan import GeneratePlan
from embodichain_ray.spec import GenerateSpec


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
            f"merge after the last batch {merge_s:.2f} s)"
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
