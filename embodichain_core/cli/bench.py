"""``embodichain bench``: run the project's benchmarks (from a source checkout).

Each benchmark is a script under ``benchmarks/`` that prints a table and writes
JSON to ``benchmarks/results/``; ratios are against raw MuJoCo in the same run.

Example:
    $ embodichain bench env --num-envs 64 --quick
    $ embodichain bench ik
"""

from __future__ import annotations

import argparse
import os
import runpy
import sys
from typing import Optional, Sequence

BENCHMARKS = {
    "env": ("env_throughput.py", "env-steps/s of an EmbodiedEnv vs raw mujoco.batch stepping"),
    "reset": ("reset_randomization.py", "reset cost with 10 randomization events vs a plain reset"),
    "render": ("render_throughput.py", "camera frames/s vs a bare mujoco.Renderer"),
    "ik": ("ik_throughput.py", "batched IK solves/s"),
    "scene": ("scene_build.py", "scene build time, cold and warm coacd cache"),
    "record": ("record_throughput.py", "recorded env-steps/s, sync vs async dataset recorder"),
}


def find_benchmarks() -> Optional[str]:
    """The ``benchmarks/`` folder of the checkout this package runs from, or of the cwd."""
    here = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    for root in (os.getcwd(), here):
        path = os.path.join(root, "benchmarks")
        if os.path.isfile(os.path.join(path, "env_throughput.py")):
            return path
    return None


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="embodichain bench", description=__doc__.splitlines()[0])
    parser.add_argument(
        "which", choices=sorted(BENCHMARKS), help="; ".join(f"{k}: {v[1]}" for k, v in BENCHMARKS.items())
    )
    parser.add_argument("args", nargs=argparse.REMAINDER, help="arguments of the benchmark script (see its --help)")
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run one benchmark script with the remaining arguments; return its exit code."""
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    folder = find_benchmarks()
    if folder is None:
        print("embodichain bench: no benchmarks/ folder found; run it from a source checkout", file=sys.stderr)
        return 2
    script = os.path.join(folder, BENCHMARKS[args.which][0])
    saved = sys.argv
    sys.argv = [script, *args.args]
    try:
        runpy.run_path(script, run_name="__main__")
    except SystemExit as done:
        return int(done.code or 0) if not isinstance(done.code, str) else 1
    finally:
        sys.argv = saved
    return 0
