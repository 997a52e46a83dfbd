"""Batched IK throughput of embodichain-robots at num_envs 64: solves per second and accuracy.

Contenders, on the same target batches (interleaved rounds, medians):

* ``DLSSolver``: the default, damped least squares on a batched torch serial chain;
* ``DLSSolver.get_ik_on_device``: the same iterations with no host read (what an
  ``EefPoseTerm`` step runs on a GPU: all ``max_iterations`` every call, no random
  restarts), here on the CPU;
* ``MjDLSSolver``: the same algorithm on MuJoCo Jacobians (``mj_kinematics`` +
  ``mj_comPos`` + ``mj_jac`` env by env on a scratch MjData): the reference;
* ``Robot.compute_ik``: the default through the Robot API in a 64-env scene
  (env-frame conversion, seeding from the current qpos).

Target modes:

* ``tracking``: targets from FK of the seed plus N(0, 0.05 rad) per joint, seeded at
  the seed (an ``EefPoseTerm`` step or ``randomize_robot_eef_pose``);
* ``random``: targets from FK of uniformly random joint values within the limits,
  seeded at the home pose (the hard case: random restarts kick in).

Accuracy: success rate, and the fraction of targets reached within 1 mm / 0.01 rad
(FK of the returned joints), with the worst errors of the successful solves.

Usage:
    python benchmarks/ik_throughput.py [--num-envs 64] [--rounds 10] [--out benchmarks/results/ik_throughput.json]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any, Callable

import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import machine_info, median, print_table, spread, write_json  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "ik_throughput.json")
COLUMNS = [
    ("robot", "robot/part", ""),
    ("solver", "solver", ""),
    ("mode", "targets", ""),
    ("solves_per_s", "solves/s", ".0f"),
    ("ms_per_batch", "ms/batch", ".2f"),
    ("spread", "spread", ".2f"),
    ("success", "success", ".3f"),
    ("within_tol", "<=1mm/0.01rad", ".3f"),
    ("max_pos_err_mm", "max pos err [mm]", ".4f"),
    ("max_rot_err_mrad", "max rot err [mrad]", ".4f"),
]


def _robots() -> dict[str, tuple[Any, str]]:
    from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg
    from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg

    return {
        "DexforceW1/left_arm": (DexforceW1Cfg.from_dict({"uid": "robot"}), "left_arm"),
        "SevenDofArm/arm": (SevenDofArmCfg.from_dict({"uid": "robot"}), "arm"),
    }


def _solvers(cfg: Any, part: str) -> dict[str, Any]:
    from embodichain_robots.kinematics.mj_solver import MjDLSSolver
    from embodichain_robots.kinematics.solver import DLSSolver

    model = cfg.build_spec().compile()
    return {
        "DLSSolver": DLSSolver.from_model(cfg.solver_cfg[part], model),
        "MjDLSSolver": MjDLSSolver.from_model(cfg.solver_cfg[part], model),
    }


def _home(cfg: Any, solver: Any, n: int) -> torch.Tensor:
    if cfg.init_qpos is None:
        return torch.zeros(n, solver.dof, dtype=torch.float64)
    return torch.as_tensor(cfg.init_qpos, dtype=torch.float64)[: solver.dof].expand(n, -1).clone()


def make_batches(cfg: Any, solver: Any, mode: str, n: int, rounds: int, seed: int = 0) -> list[tuple]:
    """``rounds`` (target (n, 4, 4), seed (n, k)) batches in the solver's root frame."""
    from embodichain_robots.kinematics.solver import sample_joint_values

    gen = torch.Generator().manual_seed(seed)
    lo, hi = solver.qpos_limits[:, 0], solver.qpos_limits[:, 1]
    out = []
    for _ in range(rounds):
        if mode == "tracking":
            start = sample_joint_values(solver.qpos_limits, n, gen)
            goal = (start + 0.05 * torch.randn(n, solver.dof, generator=gen, dtype=torch.float64)).clamp(lo, hi)
        else:
            start, goal = _home(cfg, solver, n), sample_joint_values(solver.qpos_limits, n, gen)
        out.append((solver.get_fk(goal), start))
    return out


def _accuracy(solver: Any, batches: list[tuple], results: list[tuple]) -> dict[str, float]:
    ok_all, good_all, pos_ok, rot_ok = [], [], [], []
    for (target, _), (success, qpos) in zip(batches, results):
        pos, rot = solver.pose_error(target, torch.as_tensor(qpos, dtype=torch.float64))
        ok_all.append(success)
        good_all.append((pos < 1e-3) & (rot < 0.01))
        pos_ok.append(pos[success])
        rot_ok.append(rot[success])
    pos, rot = torch.cat(pos_ok), torch.cat(rot_ok)
    return {
        "success": float(torch.cat(ok_all).float().mean()),
        "within_tol": float(torch.cat(good_all).float().mean()),
        "max_pos_err_mm": float(pos.max()) * 1e3 if len(pos) else None,
        "max_rot_err_mrad": float(rot.max()) * 1e3 if len(rot) else None,
    }


def _run(solve: Callable[[torch.Tensor, torch.Tensor], tuple], batches: list[tuple]) -> tuple[list[float], list]:
    times, results = [], []
    for target, seed in batches:
        start = time.perf_counter()
        results.append(solve(target, seed))
        times.append(time.perf_counter() - start)
    return times, results


def _seeded(solver: Any) -> Callable[[torch.Tensor, torch.Tensor], tuple]:
    """``solver.get_ik(target, qpos_seed=seed)`` as a function of ``(target, seed)``."""
    return lambda target, seed: solver.get_ik(target, qpos_seed=seed)


def bench_solvers(n: int, rounds: int, mj_rounds: int) -> list[dict[str, Any]]:
    """Rows for every contender, both modes, both robots (interleaved per round)."""
    rows = []
    for robot, (cfg, part) in _robots().items():
        solvers = _solvers(cfg, part)
        dls = solvers["DLSSolver"]
        solve = {name: (s, _seeded(s)) for name, s in solvers.items()}
        solve["DLSSolver.get_ik_on_device"] = (dls, dls.get_ik_on_device)
        for mode in ("tracking", "random"):
            batches = make_batches(cfg, dls, mode, n, rounds)
            for _, fn in solve.values():  # warm-up
                fn(*batches[0])
            per: dict[str, tuple[list, list]] = {name: ([], []) for name in solve}
            for i, batch in enumerate(batches):
                for name, (_, fn) in solve.items():
                    if name == "MjDLSSolver" and i >= mj_rounds:
                        continue
                    t, r = _run(fn, [batch])
                    per[name][0].extend(t)
                    per[name][1].extend(r)
            for name, (times, results) in per.items():
                rows.append(_row(robot, name, mode, n, times, _accuracy(solve[name][0], batches, results)))
    return rows


def bench_robot_api(n: int, rounds: int) -> list[dict[str, Any]]:
    """``Robot.compute_ik`` in a 64-env W1 scene (targets in the env frame)."""
    from embodichain_core.sim.cfg import SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    rows = []
    for robot_name, (cfg, part) in _robots().items():
        scene = Scene(SimulationManagerCfg(), num_envs=n)
        scene.add_robot(cfg)
        scene.build()
        robot = scene["robot"]
        solver = robot.get_solver(part)
        for mode in ("tracking", "random"):
            batches = make_batches(cfg, solver, mode, n, rounds, seed=1)
            base = robot.get_control_part_base_pose(part).double()
            world = [(base @ t, s) for t, s in batches]
            robot.compute_ik(world[0][0], joint_seed=world[0][1], name=part)  # warm-up
            times, results = _run(lambda t, s: robot.compute_ik(t, joint_seed=s, name=part), world)
            rows.append(_row(robot_name, "Robot.compute_ik", mode, n, times, _accuracy(solver, batches, results)))
    return rows


def _row(robot: str, solver: str, mode: str, n: int, times: list[float], acc: dict) -> dict[str, Any]:
    ms = median(times) * 1e3
    return {
        "robot": robot,
        "solver": solver,
        "mode": mode,
        "num_envs": n,
        "rounds": len(times),
        "ms_per_batch": ms,
        "solves_per_s": n / (ms / 1e3),
        "spread": spread(times),
        **acc,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--rounds", type=int, default=10)
    parser.add_argument("--mj-rounds", type=int, default=3, help="rounds for the slow MuJoCo-Jacobian reference")
    parser.add_argument("--out", default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]
    rows = bench_solvers(args.num_envs, args.rounds, args.mj_rounds) + bench_robot_api(args.num_envs, args.rounds)
    load = [load_before, os.getloadavg()[0]]
    print_table(rows, COLUMNS, title=f"Batched IK at num_envs={args.num_envs} (median of rounds)")
    from embodichain_robots.kinematics.solver import IKSolverCfg

    print(f"1-min load average before/after: {load[0]:.2f} / {load[1]:.2f} (other processes share the CPU)")
    payload = {
        "benchmark": "ik_throughput",
        "num_envs": args.num_envs,
        "machine": machine_info(),
        "load_average": load,
        "solver_defaults": IKSolverCfg().to_dict(),
        "rows": rows,
    }
    print(write_json(args.out, payload))
    return 0


if __name__ == "__main__":
    sys.exit(main())
