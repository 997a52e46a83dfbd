"""``embodichain generate``: scripted demo episodes on Ray workers, merged into one LeRobot dataset.

Example:
    $ embodichain generate --gym_config main_job.json --episodes 100 --workers 2 --seed 0 \\
          --output outputs/pick_fork_100

The config is loaded and checked exactly as ``run-env`` does it before Ray starts
(a configuration error: one line naming the key, exit 2). Without ``--ray-address``
an embedded local Ray with ``--workers`` CPUs runs the workers; with it the command
joins that cluster. Exit codes: 0 success, 1 stopped by an error (or episodes that
failed every attempt), 2 configuration error, 130 interrupted (Ctrl-C), 143 terminated
(``SIGTERM``); on both the workers stop, wait for their writers and close their shards
(at most ``--close-timeout`` seconds), and the episodes saved so far are merged.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from embodichain_core.config.errors import ConfigError
from embodichain_ray.spec import GenerateSpec
from embodichain_ray.storage import TRANSPORTS, StorageError, probe_storage, storage_target

PROG = "embodichain generate"
EXIT_ERROR, EXIT_CONFIG, EXIT_INTERRUPTED, EXIT_TERMINATED = 1, 2, 130, 143


def build_parser() -> argparse.ArgumentParser:
    """The ``generate`` argument parser."""
    p = argparse.ArgumentParser(
        prog=PROG, description="Generate scripted demo episodes on Ray workers into one merged LeRobot dataset."
    )
    p.add_argument("task", nargs="?", metavar="TASK_ID", help="gym task id (or a .json/.yaml config file)")
    p.add_argument("--gym_config", metavar="FILE", help="JSON/YAML gym config with a LeRobotRecorder")
    p.add_argument("--episodes", type=int, required=True, metavar="N", help="episodes to save")
    p.add_argument("--workers", type=int, default=1, metavar="W", help="Ray worker actors (default 1)")
    p.add_argument("--num_envs", type=int, default=1, metavar="K", help="parallel envs per worker (default 1)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="run seed: episode k uses derive_seed(S, k)")
    p.add_argument(
        "--output",
        metavar="DIR",
        help="merged dataset folder, must not exist (default outputs/generated/<task>_s<S>_n<N>)",
    )
    p.add_argument(
        "--shards", metavar="DIR", help="shard folder (default <output>.shards; shared storage on a cluster)"
    )
    p.add_argument(
        "--transport",
        default="shared",
        metavar="HOW",
        help="how shards reach the driver: shared (--shards is a folder every worker writes, the default), "
        "ray (Ray's object store) or a storage URI or folder (s3://..., gs://..., file://...)",
    )
    p.add_argument(
        "--scratch",
        metavar="DIR",
        help="with --transport ray or a URI: the folder each worker records into on its own node "
        "(default: the node's EMBODICHAIN_GENERATE_SCRATCH, else its temp folder)",
    )
    p.add_argument("--ray-address", dest="ray_address", metavar="ADDR", help="join this Ray cluster")
    p.add_argument("--max-restarts", dest="max_restarts", type=int, default=3, help="restarts per worker")
    p.add_argument(
        "--close-timeout",
        dest="close_timeout",
        type=float,
        default=60.0,
        metavar="S",
        help="on Ctrl-C or SIGTERM, seconds the workers get to finish their writes and close (default 60)",
    )
    p.add_argument("--ray-dashboard", dest="ray_dashboard", action="store_true", help="start the local Ray's dashboard")
    p.add_argument("--keep-shards", dest="keep_shards", action="store_true", help="keep the shards after merging")
    p.add_argument(
        "--merge-only",
        dest="merge_only",
        action="store_true",
        help="start no worker: merge the episodes of this run (same config, --seed, --episodes) "
        "that --shards holds, e.g. after a failed merge",
    )
    p.add_argument("--headless", action="store_true", help="no viewer (workers are always headless)")
    p.add_argument(
        "--progress-every",
        dest="progress_every",
        type=float,
        default=30.0,
        metavar="S",
        help="without a terminal (a log, CI, a scheduler): a plain progress line every S seconds (default 30)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar and no progress lines")
    return p


def spec_from_args(args: argparse.Namespace) -> GenerateSpec:
    """The run's :class:`GenerateSpec`; counts are checked here (``ConfigError`` naming the option)."""
    for name, low in (
        ("episodes", 1),
        ("workers", 1),
        ("num_envs", 1),
        ("seed", 0),
        ("max_restarts", 0),
        ("close_timeout", 0),
        ("progress_every", 0),
    ):
        if getattr(args, name) < low:
            raise ConfigError(f"--{name}", f"must be >= {low}, got {getattr(args, name)}")
    source = args.gym_config or args.task or "task"
    output = Path(args.output or f"outputs/generated/{Path(source).stem}_s{args.seed}_n{args.episodes}")
    if output.exists():
        raise ConfigError("--output", f"{output} exists; the merged dataset needs a new folder")
    check_writable_parent(output.absolute())
    transport = storage_target(args.transport)
    if transport not in TRANSPORTS:
        try:
            probe_storage(transport)
        except StorageError as err:
            raise ConfigError(
                "--transport", f"{err}; use shared, ray, a folder or a URI every worker and the driver reach"
            ) from None
    shards = Path(args.shards) if args.shards else output.with_name(output.name + ".shards")
    config = args.gym_config
    if config and Path(config).is_file():  # workers may start in another folder
        config = str(Path(config).absolute())
    return GenerateSpec(
        task=args.task,
        gym_config=config,
        episodes=args.episodes,
        workers=args.workers,
        num_envs=args.num_envs,
        seed=args.seed,
        output=output.absolute(),
        shards=shards.absolute(),
        ray_address=args.ray_address,
        max_restarts=args.max_restarts,
        keep_shards=args.keep_shards,
        merge_only=args.merge_only,
        show_bar=not args.quiet and sys.stderr.isatty(),
        close_timeout=args.close_timeout,
        dashboard=args.ray_dashboard,
        progress_every=0.0 if args.quiet else args.progress_every,
        transport=transport,
        scratch=args.scratch,
    )


def check_writable_parent(output: Path) -> None:
    """Check that the driver can create ``output``: its nearest existing folder takes a file.

    Raises:
        ConfigError: (``--output``) that folder is a file or does not take a new file.
    """
    parent = output.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ConfigError("--output", f"cannot create {output}: {parent} is not a folder")
    try:
        with tempfile.NamedTemporaryFile(dir=parent, prefix=".embodichain-probe-"):
            pass
    except OSError as err:
        raise ConfigError("--output", f"cannot create {output}: {parent} does not take a new file ({err.strerror})")


def seconds_since_process_start() -> float:
    """Seconds since this process started (Linux ``/proc``; 0.0 where that cannot be read):
    the summary's wall time then includes Python's start and the imports before ``main``."""
    try:
        with open("/proc/self/stat") as stat, open("/proc/uptime") as uptime:
            ticks = int(stat.read().rsplit(")", 1)[1].split()[19])  # field 22: starttime
            now = float(uptime.read().split()[0])
        return max(now - ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError):
        return 0.0


def main(argv: Sequence[str] | None = None, on_start: Callable[[list], None] | None = None) -> int:
    """Run ``embodichain generate`` with ``argv``; return the exit code.

    ``on_start(actors)`` runs once the worker actors exist (a test hook, see :func:`~embodichain_ray.run.generate`).
    """
    started = time.perf_counter()
    if argv is None or list(argv) == sys.argv[2:]:  # the command line: count its imports too
        started -= seconds_since_process_start()
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    from embodichain_core.cli.run_env import sigterm_as_interrupt

    with sigterm_as_interrupt():  # SIGTERM stops the run like Ctrl-C (exit 143)
        return _main(args, on_start, started)


def _main(args: argparse.Namespace, on_start: Callable[[list], None] | None, started: float) -> int:
    try:
        spec = spec_from_args(args)
        from embodichain_ray.plan import check_plan

        plan = check_plan(spec)
    except ConfigError as err:
        source = args.gym_config or args.task
        print(f"{PROG}: config error{f' in {source}' if source else ''}: {err}", file=sys.stderr)
        return EXIT_CONFIG
    from embodichain_ray.run import generate

    return generate(spec, plan, PROG, on_start, started)


if __name__ == "__main__":
    sys.exit(main())
