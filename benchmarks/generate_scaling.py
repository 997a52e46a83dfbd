"""``embodichain generate`` scaling: the main job at ``--workers 1`` and ``--workers 2`` (K = 1 each).

Both runs happen in this process, one after the other, with the same episodes (seed 0),
each on its own embedded local Ray. Per run: episodes merged, wall time (Ray start, env
builds, episodes, merge), the time the workers spent running episodes, env-steps/s and
episodes/min while the workers ran (startup excluded) and over the whole wall time, and
the merge time. Then the ratio of ``--workers 2`` to ``--workers 1`` (target >= 1.6x; the
ceiling on a 2-core machine is 2x, and other processes on the machine lower it).

``--merge-sizes`` also times the merge alone for larger datasets: the episodes of the
2-worker run are merged again, repeated up to each size (every episode is a real one of
the main job, so per-episode merge cost is what a real run of that size pays).

Usage:
    python benchmarks/generate_scaling.py [--episodes 6] [--merge-sizes 50,200] \\
        [--out benchmarks/results/generate_scaling.json]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import machine_info, print_table, write_json

DEFAULT_OUT = os.path.join("benchmarks", "results", "generate_scaling.json")
TARGET_RATIO = 1.6
COLUMNS = [
    ("workers", "W", "d"),
    ("episodes", "episodes", "d"),
    ("env_steps", "env steps", "d"),
    ("wall_s", "wall [s]", ".1f"),
    ("workers_s", "episodes [s]", ".1f"),
    ("merge_s", "merge [s]", ".1f"),
    ("steps_per_s", "env-steps/s", ".1f"),
    ("episodes_per_min", "episodes/min", ".2f"),
    ("wall_episodes_per_min", "episodes/min (wall)", ".2f"),
]
MERGE_COLUMNS = [
    ("episodes", "episodes", "d"),
    ("merge_s", "merge [s]", ".2f"),
    ("ms_per_episode", "ms/episode", ".0f"),
]


def main_job_config() -> str:
    """The main job's config file (``make run``)."""
    import embodichain_tasks

    return str(Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json")


def run(workers: int, episodes: int, folder: Path) -> dict[str, Any]:
    """One ``generate`` run of the main job; its measurements."""
    from embodichain_ray.cli import build_parser, spec_from_args
    from embodichain_ray.plan import check_plan
    from embodichain_ray.run import execute

    args = build_parser().parse_args(
        [
            "--gym_config",
            main_job_config(),
            "--episodes",
            str(episodes),
            "--workers",
            str(workers),
            "--num_envs",
            "1",
            "--seed",
            "0",
            "--output",
            str(folder / f"w{workers}"),
            "--keep-shards",
            "--quiet",
        ]
    )
    spec = spec_from_args(args)
    state = execute(spec, check_plan(spec), "generate_scaling")
    if state.code != 0:
        raise RuntimeError(f"generate --workers {workers} failed: {state.error}")
    busy = max(w.busy_s for w in state.workers)
    wall = state.run_s + state.merge_s
    return {
        "workers": workers,
        "episodes": state.merged,
        "env_steps": state.env_steps,
        "wall_s": wall,
        "workers_s": busy,
        "merge_s": state.merge_s,
        "steps_per_s": state.env_steps / busy,
        "episodes_per_min": 60.0 * state.merged / busy,
        "wall_episodes_per_min": 60.0 * state.merged / wall,
        "per_worker": [
            {"episodes": w.episodes, "failures": w.failures, "steps_per_s": w.steps_per_s, "restarts": w.restarts}
            for w in state.workers
        ],
        "shards": str(spec.shards),
    }


def merge_scaling(shards: Path, episodes: int, sizes: list[int], folder: Path) -> list[dict[str, Any]]:
    """Merge the run's episodes repeated up to each size; seconds per size."""
    from embodichain_ray.merge import merge_episodes
    from embodichain_ray.shards import scan_shards
    from embodichain_ray.spec import seed_table

    scan = scan_shards(shards, seed_table(0, episodes, 3))
    base = [scan.episodes[k] for k in sorted(scan.episodes)]
    rows = []
    for size in sizes:
        chosen = [base[i % len(base)] for i in range(size)]
        started = time.perf_counter()
        merge_episodes(chosen, folder / f"merge_{size}")
        seconds = time.perf_counter() - started
        rows.append({"episodes": size, "merge_s": seconds, "ms_per_episode": 1000.0 * seconds / size})
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=6, help="episodes per run (default 6)")
    parser.add_argument("--merge-sizes", default="50,200", help="merge-only sizes, comma-separated ('' for none)")
    parser.add_argument("--out", default=DEFAULT_OUT, help=f"JSON results (default {DEFAULT_OUT})")
    args = parser.parse_args()
    sizes = [int(s) for s in args.merge_sizes.split(",") if s.strip()]
    with tempfile.TemporaryDirectory(prefix="generate_scaling_") as tmp:
        folder = Path(tmp)
        rows = [run(w, args.episodes, folder) for w in (1, 2)]
        merges = merge_scaling(Path(rows[1]["shards"]), args.episodes, sizes, folder) if sizes else []
    ratio = rows[1]["steps_per_s"] / rows[0]["steps_per_s"]
    wall_ratio = rows[1]["wall_episodes_per_min"] / rows[0]["wall_episodes_per_min"]
    print_table(rows, COLUMNS, title=f"embodichain generate, main job, K=1, {args.episodes} episodes")
    print(
        f"speed-up W=2 / W=1: {ratio:.2f}x while the workers ran, {wall_ratio:.2f}x over the wall time "
        f"(target >= {TARGET_RATIO}x)"
    )
    if merges:
        print_table(merges, MERGE_COLUMNS, title="merge alone (episodes of the W=2 run, repeated)")
    for row in rows:
        row.pop("shards")
    payload = {
        "machine": machine_info(),
        "episodes": args.episodes,
        "runs": rows,
        "ratio": ratio,
        "wall_ratio": wall_ratio,
        "target_ratio": TARGET_RATIO,
        "merge": merges,
    }
    print(f"wrote {write_json(args.out, payload)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
