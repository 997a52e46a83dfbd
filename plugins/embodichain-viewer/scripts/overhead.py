"""Env steps per second of a task headless and with the browser viewer open (no page
connected, and the viewer's own thread drawing every snapshot into its scene).

    $ .venv/bin/python plugins/embodichain-viewer/scripts/overhead.py --task PushCube-v1 --num_envs 16
"""

from __future__ import annotations

import argparse
import time

import torch


def steps_per_second(task: str, num_envs: int, viewer: str, steps: int) -> float:
    """Env-steps/s over ``steps`` control steps of zero actions (after 20 warm-up steps)."""
    from embodichain_core.cli.run_env import build_parser, make_env, prepare

    argv = [task, "--num_envs", str(num_envs), "--quiet"] + (
        ["--viewer", viewer] if viewer != "none" else ["--headless"]
    )
    env = make_env(prepare(build_parser().parse_args(argv)))
    try:
        env.reset(seed=0)
        action = torch.zeros(env.unwrapped.action_space.shape)
        for _ in range(20):
            env.step(action)
        start = time.perf_counter()
        for _ in range(steps):
            env.step(action)
        return steps * num_envs / (time.perf_counter() - start)
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="PushCube-v1")
    parser.add_argument("--num_envs", type=int, default=16)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    for viewer in ("none", "browser") * args.repeats:
        rate = steps_per_second(args.task, args.num_envs, viewer, args.steps)
        print(f"{args.task} num_envs={args.num_envs} viewer={viewer:8s} {rate:9.0f} env-steps/s")


if __name__ == "__main__":
    main()
