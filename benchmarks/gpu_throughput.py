"""Env throughput of PushCube-v1 on the ``warp`` backend against raw MuJoCo Warp stepping.

The env: ``gym.make("PushCube-v1")`` with ``sim_cfg.backend = "warp"`` on ``--device``
(a 7-DoF arm pushes a cube; its own reset events, observations and rewards; episodes of
100 steps with auto-resets), driven by precomputed random actions already on the device.

The baseline: MuJoCo Warp itself on the SAME compiled model (``env.scene.model``), with
the env's world count and contact/constraint buffer sizes, starting from the env's state:
per env step it writes ``ctrl`` and replays one CUDA graph of
``sim_steps_per_control * physics_substeps`` ``mujoco_warp.step`` calls (the least any
env can do). Env and raw rounds are interleaved ``--repeats`` times after a warm-up;
medians are reported. ``ratio = env env-steps/s / raw env-steps/s``.

Targets on one H100 (issue 20): >= 100 000 env-steps/s at 4 096 envs, ratio >= 0.8.
``--smoke`` runs 8 envs for a few steps on Warp's CPU device (a correctness run of this
script, not a measurement).

Usage:
    python benchmarks/gpu_throughput.py [--device cuda] [--num-envs 1024 4096 8192]
        [--steps 100] [--repeats 5] [--out benchmarks/results/gpu_throughput.json] [--smoke]
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import TYPE_CHECKING, Any, Callable

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import interleaved_timings, machine_info, median, print_table, spread, write_json  # noqa: E402

if TYPE_CHECKING:  # torch, gymnasium and the plugins load in make_env (a bad argument fails fast)
    import torch

DEFAULT_OUT = os.path.join("benchmarks", "results", "gpu_throughput.json")
TARGET_STEPS_PER_S_AT_4096 = 100_000
TARGET_RATIO = 0.8
ACTION_PERIOD = 50


def make_env(num_envs: int, device: str) -> Any:
    """PushCube-v1 on the warp backend, reset once."""
    import gymnasium as gym

    import embodichain_core  # noqa: F401  (loads the plugins: PushCube-v1)
    from embodichain_tasks.rl.push_cube import PushCubeCfg

    cfg = PushCubeCfg()
    cfg.sim_cfg.backend = "warp"
    cfg.sim_cfg.sim_device = device
    env = gym.make("PushCube-v1", cfg=cfg, num_envs=num_envs, seed=0, verbose=False).unwrapped
    env.reset(seed=0)
    return env


def raw_stepper(env: Any) -> tuple[Callable[[torch.Tensor], None], Callable[[], None]]:
    """``(step(ctrl), sync)`` of bare MuJoCo Warp on the env's model, world count and buffers."""
    import mujoco
    import mujoco_warp as mjw

    from embodichain_core.sim.backend.warp_device import StepGraphs
    from embodichain_core.sim.backend.warp_sim import _warp_ready

    sim, wp = env.sim, env.sim.wp
    mjm = _warp_ready(env.scene.model)
    with wp.ScopedDevice(sim.wp_device):
        model = mjw.put_model(mjm)
        data = mjw.put_data(mjm, mujoco.MjData(mjm), nworld=sim.num_envs, nconmax=sim.nconmax, njmax=sim.njmax)
    for name in ("qpos", "qvel"):
        wp.to_torch(getattr(data, name)).copy_(sim.view(name))
    ctrl, n = wp.to_torch(data.ctrl), env.sim_steps_per_control * sim.substeps
    graphs = StepGraphs(wp, sim.wp_device)

    def advance() -> None:
        for _ in range(n):
            mjw.step(model, data)

    def step(action_ctrl: torch.Tensor) -> None:
        ctrl[:, : action_ctrl.shape[1]] = action_ctrl
        graphs.run("step", advance)

    return step, lambda: wp.synchronize_device(sim.wp_device)


def measure(num_envs: int, device: str, steps: int, repeats: int) -> dict[str, Any]:
    """One row: env and raw env-steps/s at ``num_envs``."""
    import torch

    env = make_env(num_envs, device)
    gen = torch.Generator().manual_seed(0)
    shape = env.action_space.shape
    actions = [(torch.rand(shape, generator=gen) * 2 - 1).to(env.device) * 0.5 for _ in range(ACTION_PERIOD)]
    raw_step, sync = raw_stepper(env)
    raw_ctrl = [a.to(env.sim.device) for a in actions]

    def run_env() -> None:
        for t in range(steps):
            env.step(actions[t % ACTION_PERIOD])
        sync()

    def run_raw() -> None:
        for t in range(steps):
            raw_step(raw_ctrl[t % ACTION_PERIOD])
        sync()

    times = interleaved_timings({"env": run_env, "raw": run_raw}, repeats)
    env_rate, raw_rate = num_envs * steps / median(times["env"]), num_envs * steps / median(times["raw"])
    mujoco_steps = env.sim_steps_per_control * env.sim.substeps
    env.close()
    return {
        "num_envs": num_envs,
        "device": device,
        "steps": steps,
        "repeats": repeats,
        "mujoco_steps_per_env_step": mujoco_steps,
        "env_steps_per_s": env_rate,
        "raw_steps_per_s": raw_rate,
        "ratio": env_rate / raw_rate,
        "env_spread": spread(times["env"]),
        "raw_spread": spread(times["raw"]),
        "env_times_s": times["env"],
        "raw_times_s": times["raw"],
    }


def parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cuda", help="Warp device: cuda, cuda:N or cpu")
    parser.add_argument("--num-envs", type=int, nargs="+", default=[1024, 4096, 8192])
    parser.add_argument("--steps", type=int, default=100, help="env steps per timed round")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved rounds per contender")
    parser.add_argument("--out", default=DEFAULT_OUT, help="JSON results ('' for none)")
    parser.add_argument("--smoke", action="store_true", help="8 envs, 3 steps, 1 round on Warp's CPU device")
    args = parser.parse_args(argv)
    if args.smoke:
        args.device, args.num_envs, args.steps, args.repeats = "cpu", [8], 3, 1
    for name in ("steps", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be positive")
    if any(n < 1 for n in args.num_envs):
        parser.error("--num-envs must be positive")
    return args


def main(argv: list[str] | None = None) -> dict[str, Any]:
    args = parse(argv)
    rows = [measure(n, args.device, args.steps, args.repeats) for n in args.num_envs]
    columns = [
        ("num_envs", "num_envs", "d"),
        ("env_steps_per_s", "env steps/s", ".0f"),
        ("raw_steps_per_s", "raw MuJoCo Warp steps/s", ".0f"),
        ("ratio", "ratio", ".2f"),
    ]
    print_table(rows, columns, title=f"PushCube-v1 on the warp backend, device {args.device}")
    at_4096 = [r for r in rows if r["num_envs"] == 4096]
    payload = {
        "benchmark": "gpu_throughput",
        "settings": vars(args),
        "machine": machine_info(),
        "targets": {"env_steps_per_s_at_4096": TARGET_STEPS_PER_S_AT_4096, "ratio": TARGET_RATIO},
        "meets_targets": (
            bool(at_4096[0]["env_steps_per_s"] >= TARGET_STEPS_PER_S_AT_4096 and at_4096[0]["ratio"] >= TARGET_RATIO)
            if at_4096
            else None
        ),
        "results": rows,
    }
    if args.out:
        write_json(args.out, payload)
        print(f"wrote {args.out}")
    return payload


if __name__ == "__main__":
    main()
