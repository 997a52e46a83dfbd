"""What a small tensor op costs right after the physics call: the cold-cache price of a functor.

Between two env steps a ``Batch.step`` runs MuJoCo on every core, the caller's thread
included, for milliseconds. The Python that follows (the env loop and every functor) then
finds its code and data out of the CPU's caches and branch predictors. This script times
the same short probe of small torch and numpy ops (the first of each kind in an iteration,
then a repeat of them) after:

* ``nothing``: back to back (warm caches);
* ``batch`` : ``Batch.step`` of ``num_envs`` envs of the benchmark scene of
  ``env_throughput.py`` (20 MuJoCo steps each);
* ``sleep`` : ``time.sleep`` for as long as that step took (the thread idles);
* ``spin``  : a Python busy loop for as long (the thread keeps running).

``docs/performance.md`` ("Costs to keep in mind when writing tasks") draws the lesson for
functor authors. No timing is asserted anywhere; the numbers are medians of ``--rounds``.

Usage:
    python benchmarks/cold_ops.py [--num-envs 1 16 64] [--rounds 200] [--out PATH]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any, Callable, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import mujoco  # noqa: E402
import mujoco.batch as mjbatch  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402

from common import machine_info, median, print_table, write_json  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "cold_ops.json")
NSTEP = 20  # MuJoCo steps per env step in env_throughput.py
#: The probe's parts, timed one by one: (name, op). Each returns nothing of interest.
PROBE: list[tuple[str, Callable[[], Any]]] = [
    ("torch.zeros", lambda: torch.zeros(7, 6, dtype=torch.float64)),
    ("torch.rand", lambda: torch.rand(7, 2, dtype=torch.float64)),
    ("torch arith", lambda: (torch.ones(7, 2, dtype=torch.float64) * 2 - 1) * 0.2),
    ("numpy.zeros", lambda: np.zeros((7, 6))),
    ("numpy random", lambda: np.random.random((7, 2))),
    ("numpy arith", lambda: (np.ones((7, 2)) * 2 - 1) * 0.2),
]


def probe() -> list[float]:
    """Microseconds of each :data:`PROBE` op, first touch, then the same ops again (sum)."""
    out = []
    for _, op in PROBE:
        start = time.perf_counter_ns()
        op()
        out.append((time.perf_counter_ns() - start) / 1e3)
    start = time.perf_counter_ns()
    for _, op in PROBE:
        op()
    out.append((time.perf_counter_ns() - start) / 1e3)
    return out


def timed_probe(between: Callable[[], Any], rounds: int, warmup: int = 10) -> list[float]:
    """Median of each probe part over ``rounds`` iterations of ``between(); probe()``."""
    for _ in range(warmup):
        between()
        probe()
    samples = []
    for _ in range(rounds):
        between()
        samples.append(probe())
    return [median([s[i] for s in samples]) for i in range(len(samples[0]))]


def _spin(seconds: float) -> Callable[[], None]:
    def spin() -> None:
        end = time.perf_counter() + seconds
        while time.perf_counter() < end:
            pass

    return spin


def benchmark_model() -> mujoco.MjModel:
    """The compiled scene of ``env_throughput.py`` (arm, table, 3 cubes)."""
    from env_throughput import make_env

    env = make_env(1)
    model = env.unwrapped.scene.model
    env.close()
    return model


def measure(model: mujoco.MjModel, num_envs: int, rounds: int) -> list[dict[str, Any]]:
    """One record per ``between`` kind for ``num_envs`` envs."""
    batch = mjbatch.Batch(model, num_envs, nthread=min(os.cpu_count() or 1, num_envs), persistent=True)
    batch.reset(None)
    stage = int(mujoco.mjtStage.mjSTAGE_VEL)

    def step() -> None:
        batch.step(None, NSTEP, stage)

    step()
    start = time.perf_counter()
    for _ in range(5):
        step()
    step_s = (time.perf_counter() - start) / 5
    kinds = {"nothing": lambda: None, "batch": step, "sleep": lambda: time.sleep(step_s), "spin": _spin(step_s)}
    warm = None
    records = []
    for kind, between in kinds.items():
        parts = timed_probe(between, rounds)
        warm = warm or parts
        rec: dict[str, Any] = {
            "num_envs": num_envs,
            "between": kind,
            "between_ms": 0.0 if kind == "nothing" else step_s * 1e3,
        }
        rec.update({name: parts[i] for i, (name, _) in enumerate(PROBE)})
        rec["repeat of all"] = parts[-1]
        rec["first touch / warm"] = sum(parts[: len(PROBE)]) / max(sum(warm[: len(PROBE)]), 1e-9)
        records.append(rec)
    return records


def parse_args(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--num-envs", type=int, nargs="+", default=[1, 16, 64], help="batch sizes (default 1 16 64)")
    p.add_argument("--rounds", type=int, default=200, help="probes per kind; medians are reported")
    p.add_argument("--out", default=DEFAULT_OUT, help=f"JSON output (default {DEFAULT_OUT}; '' writes none)")
    args = p.parse_args(argv)
    if any(n < 1 for n in args.num_envs) or args.rounds < 1:
        p.error("--num-envs and --rounds must be positive")
    return args


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = parse_args(argv)
    torch.set_grad_enabled(False)
    model = benchmark_model()
    records = [rec for n in args.num_envs for rec in measure(model, n, args.rounds)]
    columns = [("num_envs", "num_envs", "d"), ("between", "between", "s"), ("between_ms", "ms", ".2f")]
    columns += [(name, f"{name} us", ".1f") for name, _ in PROBE]
    columns += [("repeat of all", "repeat of all us", ".1f"), ("first touch / warm", "first touch / warm", ".1f")]
    print_table(records, columns, title=f"Small ops right after ... (median of {args.rounds} probes)")
    payload = {"benchmark": "cold_ops", "settings": vars(args), "machine": machine_info(), "records": records}
    if args.out:
        print(f"wrote {write_json(args.out, payload)}")
    return payload


if __name__ == "__main__":
    main()
