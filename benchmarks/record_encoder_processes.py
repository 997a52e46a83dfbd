"""Recorded env-steps/s and CPU seconds per env-step with the videos encoded by the dataset
writer process (``encoder_processes: 1``) or spread over N encoder processes.

The env of ``record_throughput.py``: the 7-DoF arm, a cube, a light and a stereo camera
(``--size``, colour only), every episode succeeding at ``--episode-length`` steps (ends
staggered across envs), recorded by ``AsyncLeRobotRecorder`` with streamed videos
(``--vcodec``). Each run is its own process (a fresh recorder, writer and encoder
processes); after a warm-up (one episode per env, written: lerobot is imported in every
child by then) it times ``--steps`` env steps and the close that flushes the last episodes.
Reported per encoder-process count (medians over ``--repeats`` runs, interleaved):

* ``env_steps_per_s``: what the stepping loop sees (``steps * num_envs / t``);
* ``end_to_end_steps_per_s``: including the final flush (every episode saved);
* ``cpu_ms_per_env_step``: CPU time of the recording process and all its children (writer,
  encoders) over the timed steps and the flush, per env step.

Usage:
    python benchmarks/record_encoder_processes.py [--encoder-processes 1 2] [--num-envs 4]
        [--steps 200] [--episode-length 50] [--size 128 128] [--vcodec libsvtav1]
        [--repeats 3] [--out benchmarks/results/record_encoder_processes.json] [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from typing import Any, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")
os.environ.setdefault("SVT_LOG", "1")

DEFAULT_OUT = os.path.join("benchmarks", "results", "record_encoder_processes.json")


def _proc_cpu(pid: Optional[int]) -> float:
    """CPU seconds process ``pid`` has used so far (0 when it is gone)."""
    try:
        fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    except (OSError, IndexError, TypeError):
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _own_cpu(who: int) -> float:
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def run_one(count: int, args: argparse.Namespace) -> dict[str, Any]:
    """One recording with ``count`` encoder processes (in this process)."""
    from record_throughput import actions, make_cfg, make_env

    with tempfile.TemporaryDirectory(prefix="enc-bench-") as workdir:
        cfg = make_cfg(
            args.num_envs, "AsyncLeRobotRecorder", workdir, "video", tuple(args.size), False, args.episode_length
        )
        cfg.dataset["rec"].params.update(vcodec=args.vcodec, encoder_processes=count)
        env = make_env(cfg, args.episode_length)
        rec, moves = env.dataset_manager.get_functor("rec"), actions(env.num_envs)
        for k in range(args.episode_length + 1):  # warm-up: every env commits an episode, written
            env.step(moves[k % len(moves)])
        rec.wait()
        pool = rec._encoders.processes if rec._encoders is not None else []
        children = [rec._writer_process.pid, *(p.pid for p in pool)]
        cpu0 = _own_cpu(resource.RUSAGE_SELF) + sum(_proc_cpu(pid) for pid in children)
        before_children = _own_cpu(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        for k in range(args.steps):
            env.step(moves[k % len(moves)])
        stepped = time.perf_counter()
        env.close()  # the flush: every committed episode saved, the children stopped and reaped
        done = time.perf_counter()
        cpu1 = _own_cpu(resource.RUSAGE_SELF) + _own_cpu(resource.RUSAGE_CHILDREN) - before_children
        env_steps = args.steps * args.num_envs
        return {
            "encoder_processes": count,
            "env_steps_per_s": env_steps / (stepped - start),
            "end_to_end_steps_per_s": env_steps / (done - start),
            "cpu_ms_per_env_step": 1000 * (cpu1 - cpu0) / env_steps,
            "episodes_saved": rec.saved_episodes,
        }


def _parse(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--encoder-processes", type=int, nargs="+", default=[1, 2])
    p.add_argument("--num-envs", type=int, default=4)
    p.add_argument("--steps", type=int, default=200, help="timed env.step calls per run")
    p.add_argument("--episode-length", type=int, default=50)
    p.add_argument("--size", type=int, nargs=2, default=[128, 128], metavar=("W", "H"))
    p.add_argument("--vcodec", default="libsvtav1", choices=("libsvtav1", "h264", "hevc", "auto"))
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--out", default=DEFAULT_OUT, help="JSON output ('' writes none)")
    p.add_argument("--quick", action="store_true", help="2 envs, 32x32, 20 steps, 1 run each: checks the script runs")
    p.add_argument("--one", type=int, default=None, help=argparse.SUPPRESS)  # a single run, JSON on stdout
    args = p.parse_args(argv)
    if args.quick:
        args.num_envs, args.size, args.steps, args.episode_length, args.repeats = 2, [32, 32], 20, 10, 1
    return args


def _child_argv(count: int, args: argparse.Namespace) -> list[str]:
    return [
        sys.executable, os.path.abspath(__file__), "--one", str(count), "--num-envs", str(args.num_envs),
        "--steps", str(args.steps), "--episode-length", str(args.episode_length), "--vcodec", args.vcodec,
        "--size", *map(str, args.size),
    ]  # fmt: skip


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    from common import machine_info, median, print_table, write_json

    args = _parse(argv)
    if args.one is not None:
        print(json.dumps(run_one(args.one, args)), flush=True)
        return {}
    runs: dict[int, list[dict]] = {n: [] for n in args.encoder_processes}
    for _ in range(max(1, args.repeats)):
        for n in args.encoder_processes:  # interleaved: the machine's load hits every count alike
            out = subprocess.run(_child_argv(n, args), check=True, capture_output=True, text=True).stdout
            runs[n].append(json.loads(out.strip().splitlines()[-1]))
    keys = ("env_steps_per_s", "end_to_end_steps_per_s", "cpu_ms_per_env_step")
    rows = [
        {"encoder_processes": n, **{k: median([r[k] for r in rs]) for k in keys}, "runs": rs} for n, rs in runs.items()
    ]
    columns = [
        ("encoder_processes", "encoder procs", "d"),
        ("env_steps_per_s", "steps/s", ".1f"),
        ("end_to_end_steps_per_s", "end-to-end/s", ".1f"),
        ("cpu_ms_per_env_step", "CPU ms/env-step", ".2f"),
    ]
    print_table(rows, columns, title=f"{args.num_envs} envs, {args.size[0]}x{args.size[1]} stereo, {args.vcodec}")
    result = {"machine": machine_info(), "args": {k: v for k, v in vars(args).items() if k != "one"}, "rows": rows}
    if args.out:
        write_json(args.out, result)
    return result


if __name__ == "__main__":
    main()
