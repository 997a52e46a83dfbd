"""Env throughput of an ``EmbodiedEnv`` against raw ``mujoco.batch.Batch`` stepping.

The env: the 7-DoF arm with a two-finger gripper, 3 dynamic cubes on a kinematic
table and a point light, no cameras. Manager load: 2 reset events (cube poses
and arm joints randomized per env with ``env.generator``), 1 interval event
(random pushes of the cubes), 3 observation ``add`` functors and 3 reward
terms. Actions are joint position targets of the 7 arm joints (control part
``arm``); episodes are 100 env steps, staggered across envs as in RL training
(so partial auto-resets happen along the way and are part of the cost).

The baseline: a second ``mujoco.batch.Batch`` on the SAME compiled model
(``env.unwrapped.scene.model``), with the settings ``BatchSim`` uses
(``persistent=True``, ``stage=mjSTAGE_VEL``, ``nthread=min(cpu_count, num_envs)``),
starting from the env's state and driven by the same joint targets, stepping
``sim_steps_per_control * physics_substeps`` MuJoCo steps per env step. Its loop
is the least any env can do: write ``ctrl``, call ``Batch.step``.

A third contender, the matched twin (:mod:`matched_twin`), does the same physics work
as the env in plain numpy (the same pushes, resets and forwards), so
``ratio_matched = t_matched / t_env`` is what the framework itself costs, where
``ratio`` also counts the physics the manager load adds (sliding, colliding cubes).

Env, raw and twin runs are interleaved, ``--repeats`` times after a warm-up; medians
are reported. ``ratio = env env-steps/s / raw env-steps/s`` and
``manager_overhead_ms = (t_env - t_raw) / calls``.

Usage:
    python benchmarks/env_throughput.py [--num-envs 1 16 64 256] [--steps N]
        [--repeats R] [--out benchmarks/results/env_throughput.json] [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import Any, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import mujoco  # noqa: E402
import mujoco.batch as mjbatch  # noqa: E402
import torch  # noqa: E402

from common import (
    cycling,
    interleaved_timings,
    machine_info,
    median,
    print_table,
    seven_dof_arm_mjcf,
    spread,
    time_once,
    write_json,
)  # noqa: E402
from matched_twin import MatchedTwin, Workload  # noqa: E402
from step_breakdown import breakdown as step_breakdown  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402
from embodichain_core.managers import EventCfg, ObservationCfg, RewardCfg, SceneEntityCfg  # noqa: E402
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.shapes import CubeCfg  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "env_throughput.json")
TARGET_RATIO_AT_64 = 0.7
#: The step-overhead targets (num_envs -> ratio), checked against both baselines in the summary.
STEP_OVERHEAD_TARGETS = {1: 0.6, 16: 0.8, 64: 0.9}
TABLE_TOP = 0.32
CUBE = 0.05
CUBE_UIDS = ("cube0", "cube1", "cube2")
ACTION_PERIOD = 50  # distinct precomputed actions, cycled
#: The events' numbers (make_cfg configures them; the matched raw twin repeats them in numpy).
WORKLOAD = dict(
    cube_uids=CUBE_UIDS,
    arm_part="arm",
    push_interval=10,
    max_speed=0.2,
    xy_low=(0.35, -0.3),
    xy_high=(0.7, 0.3),
    cube_z=TABLE_TOP + CUBE / 2,
    arm_noise=0.1,
)


# -- functors (written the way a task author would, with the public entity API) -------------------
def randomize_cube_poses(env: Any, env_ids: torch.Tensor, cube_cfgs: list, xy_range: list, z: float) -> None:
    """Reset event: each cube at a random xy on the table with a random yaw."""
    n = len(env_ids)
    low = torch.tensor(xy_range[0], dtype=torch.float64)
    high = torch.tensor(xy_range[1], dtype=torch.float64)
    for cfg in cube_cfgs:
        pose = torch.zeros(n, 7, dtype=torch.float64)
        pose[:, :2] = low + (high - low) * torch.rand(n, 2, generator=env.generator, dtype=torch.float64)
        pose[:, 2] = z
        yaw = (torch.rand(n, generator=env.generator, dtype=torch.float64) * 2 - 1) * math.pi
        pose[:, 3] = torch.cos(yaw / 2)
        pose[:, 6] = torch.sin(yaw / 2)
        env.scene[cfg.uid].set_local_pose(pose, env_ids)


def randomize_arm_joints(env: Any, env_ids: torch.Tensor, entity_cfg: SceneEntityCfg, noise: float) -> None:
    """Reset event: arm joints at their defaults plus uniform noise (teleport + targets)."""
    robot = env.scene[entity_cfg.uid]
    jids = torch.as_tensor(entity_cfg.joint_ids, dtype=torch.long)
    q = robot.default_qpos[jids].to(torch.float64).expand(len(env_ids), -1)
    q = q + (torch.rand(len(env_ids), len(jids), generator=env.generator, dtype=torch.float64) * 2 - 1) * noise
    robot.set_qpos(q, joint_ids=jids, env_ids=env_ids, target=False)


def push_cubes(env: Any, env_ids: torch.Tensor, cube_cfgs: list, max_speed: float) -> None:
    """Interval event: give the cubes of ``env_ids`` a random horizontal velocity."""
    n = len(env_ids)
    for cfg in cube_cfgs:
        vel = torch.zeros(n, 6, dtype=torch.float64)
        vel[:, :2] = (torch.rand(n, 2, generator=env.generator, dtype=torch.float64) * 2 - 1) * max_speed
        env.scene[cfg.uid].set_velocity(vel, env_ids)


def cube_poses(env: Any, obs: dict, cube_cfgs: list) -> torch.Tensor:
    """Observation: (N, 3 * 7) poses of the cubes."""
    return torch.cat([env.scene[c.uid].get_local_pose() for c in cube_cfgs], dim=-1)


def ee_pose(env: Any, obs: dict, entity_cfg: SceneEntityCfg, link: str) -> torch.Tensor:
    """Observation: (N, 7) pose of the hand link."""
    return env.scene[entity_cfg.uid].get_link_pose(link)


def cube_to_ee(env: Any, obs: dict, entity_cfg: SceneEntityCfg, cube_cfg: SceneEntityCfg, link: str) -> torch.Tensor:
    """Observation: (N, 3) vector from the hand to the first cube."""
    hand = env.scene[entity_cfg.uid].get_link_pose(link)[:, :3]
    return env.scene[cube_cfg.uid].get_local_pose()[:, :3] - hand


def reach_reward(env: Any, obs: dict, action: Any, info: dict) -> torch.Tensor:
    """Reward: closeness of the hand to the first cube (from the observation)."""
    return torch.exp(-4.0 * obs["task"]["cube_to_ee"].norm(dim=-1))


def lift_reward(
    env: Any, obs: dict, action: Any, info: dict, cube_cfg: SceneEntityCfg, table_top: float
) -> torch.Tensor:
    """Reward: height of the first cube above the table."""
    z = env.scene[cube_cfg.uid].get_local_pose()[:, 2]
    return (z - table_top - CUBE / 2).clamp(min=0.0)


def joint_velocity_penalty(env: Any, obs: dict, action: Any, info: dict) -> torch.Tensor:
    """Reward: squared joint speed of the arm."""
    return obs["robot"]["qvel"].square().sum(dim=-1)


def make_cfg(num_envs: int, sim_steps_per_control: int = 4, episode_length: int = 100, seed: int = 0) -> EmbodiedEnvCfg:
    """The benchmark env's config."""
    cubes = [SceneEntityCfg(uid=u) for u in CUBE_UIDS]
    arm = SceneEntityCfg(uid="arm", joint_names=["joint[1-7]"])
    rigid = [
        RigidObjectCfg(uid=u, shape=CubeCfg(size=[CUBE] * 3), init_pos=(0.45, -0.15 + 0.15 * i, TABLE_TOP + CUBE / 2))
        for i, u in enumerate(CUBE_UIDS)
    ]
    table = RigidObjectCfg(
        uid="table", shape=CubeCfg(size=[0.6, 0.9, 0.04]), body_type="kinematic", init_pos=(0.55, 0.0, TABLE_TOP - 0.02)
    )
    events = {
        "reset_cubes": EventCfg(
            func=randomize_cube_poses,
            mode="reset",
            params={
                "cube_cfgs": cubes,
                "xy_range": [list(WORKLOAD["xy_low"]), list(WORKLOAD["xy_high"])],
                "z": WORKLOAD["cube_z"],
            },
        ),
        "reset_arm": EventCfg(
            func=randomize_arm_joints, mode="reset", params={"entity_cfg": arm, "noise": WORKLOAD["arm_noise"]}
        ),
        "push_cubes": EventCfg(
            func=push_cubes,
            mode="interval",
            interval_step=WORKLOAD["push_interval"],
            params={"cube_cfgs": cubes, "max_speed": WORKLOAD["max_speed"]},
        ),
    }
    observations = {
        "cube_poses": ObservationCfg(
            func=cube_poses, mode="add", name="object/cube_poses", params={"cube_cfgs": cubes}
        ),
        "ee_pose": ObservationCfg(
            func=ee_pose,
            mode="add",
            name="robot/ee_pose",
            params={"entity_cfg": SceneEntityCfg(uid="arm"), "link": "hand"},
        ),
        "cube_to_ee": ObservationCfg(
            func=cube_to_ee,
            mode="add",
            name="task/cube_to_ee",
            params={"entity_cfg": SceneEntityCfg(uid="arm"), "cube_cfg": SceneEntityCfg(uid="cube0"), "link": "hand"},
        ),
    }
    rewards = {
        "reach": RewardCfg(func=reach_reward, weight=1.0),
        "lift": RewardCfg(
            func=lift_reward, weight=5.0, params={"cube_cfg": SceneEntityCfg(uid="cube0"), "table_top": TABLE_TOP}
        ),
        "joint_vel": RewardCfg(func=joint_velocity_penalty, weight=-1e-3),
    }
    return EmbodiedEnvCfg(
        num_envs=num_envs,
        seed=seed,
        sim_steps_per_control=sim_steps_per_control,
        max_episode_steps=episode_length,
        verbose=False,
        robot=RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]}),
        control_parts=["arm"],
        rigid_object=rigid,
        background=[table],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="point", init_pos=(0.0, 0.0, 2.0))]),
        events=events,
        observations=observations,
        rewards=rewards,
    )


def make_env(num_envs: int, sim_steps_per_control: int = 4, episode_length: int = 100, seed: int = 0) -> EmbodiedEnv:
    """Build and reset the benchmark env; episodes are staggered across envs."""
    env = EmbodiedEnv(make_cfg(num_envs, sim_steps_per_control, episode_length, seed))
    env.reset(seed=seed)
    # Stagger episode ends as in RL training (Isaac Lab randomizes episode_length_buf the
    # same way), so partial auto-resets happen at a steady rate inside every timed window.
    stagger = torch.randint(0, episode_length, (num_envs,), generator=torch.Generator().manual_seed(seed))
    env.unwrapped._elapsed_steps[:] = stagger.to(env.unwrapped._elapsed_steps.dtype)
    return env


def make_actions(env: EmbodiedEnv, period: int = ACTION_PERIOD) -> list[torch.Tensor]:
    """``period`` smooth (N, 7) joint-target actions around the default pose."""
    robot = env.unwrapped.robot
    jids = robot.get_joint_ids("arm")
    n = env.unwrapped.num_envs
    base = robot.default_qpos[jids].to(torch.float32)
    phase = torch.linspace(0, 2 * math.pi, n + 1)[:n, None] + torch.arange(len(jids))[None, :] * 0.7
    out = []
    for k in range(period):
        t = 2 * math.pi * k / period
        out.append((base + 0.4 * torch.sin(phase + t)).contiguous())
    return out


# -- measurement ------------------------------------------------------------------------------------
def measure(
    num_envs: int,
    sim_steps_per_control: int = 4,
    steps: Optional[int] = None,
    repeats: int = 7,
    warmup_steps: int = 20,
    target_seconds: float = 0.6,
    episode_length: int = 100,
    seed: int = 0,
    breakdown: bool = True,
    clock: str = "wall",
) -> dict[str, Any]:
    """One configuration: env and raw timings, interleaved; returns the JSON record.

    With ``breakdown``, a second, instrumented pass (:mod:`step_breakdown`) times the
    MuJoCo calls and the functors inside ``env.step`` (reported under ``breakdown``,
    with the ceiling ratio; the headline numbers come from the
    uninstrumented pass).
    """
    env = make_env(num_envs, sim_steps_per_control, episode_length, seed)
    base = env.unwrapped
    stagger = base._elapsed_steps.numpy().copy()
    model = base.scene.model
    substeps = base.sim.substeps
    nstep = sim_steps_per_control * substeps
    nthread = min(os.cpu_count() or 1, num_envs)
    actions = make_actions(env)
    robot = base.robot
    arm_acts = robot.pos_act[robot.get_joint_ids("arm")].numpy()
    actions_np = [a.to(torch.float64).numpy() for a in actions]

    raw = mjbatch.Batch(model, num_envs, nthread=nthread, persistent=True)
    raw.reset(None)
    raw.state[...] = base.sim.state  # same starting state (cubes on the table, same targets)
    raw.forward(None, stage=mujoco.mjtStage.mjSTAGE_VEL)
    ctrl = raw.bind("ctrl")
    stage = mujoco.mjtStage.mjSTAGE_VEL

    twin = MatchedTwin(base, nthread, nstep, stagger, Workload(episode_length=episode_length, **WORKLOAD), seed)

    def raw_step(action: Any) -> None:
        ctrl[:, arm_acts] = action
        raw.step(nstep=nstep, stage=stage)

    run_env, run_raw = cycling(env.step, actions), cycling(raw_step, actions_np)
    run_matched = cycling(twin.step, actions_np)

    # warm-up (also sizes the timed window when --steps is not given)
    t_env_w = time_once(lambda: run_env(warmup_steps))
    t_raw_w = time_once(lambda: run_raw(warmup_steps))
    time_once(lambda: run_matched(warmup_steps))
    if steps is None:
        per_call = max(t_env_w, t_raw_w) / max(1, warmup_steps)
        steps = int(min(20000, max(20, round(target_seconds / max(per_call, 1e-6)))))

    times = interleaved_timings(
        {"env": lambda: run_env(steps), "raw": lambda: run_raw(steps), "matched": lambda: run_matched(steps)},
        repeats=repeats,
        warmup=0,
        clock=clock,
    )
    t_env, t_raw, t_matched = median(times["env"]), median(times["raw"]), median(times["matched"])
    env_sps = steps * num_envs / t_env
    raw_sps = steps * num_envs / t_raw
    paired = [r / e for e, r in zip(times["env"], times["raw"])]
    parts = step_breakdown(base, run_env, run_raw, steps, min(3, repeats)) if breakdown else None
    env.close()
    return {
        "num_envs": num_envs,
        "sim_steps_per_control": sim_steps_per_control,
        "physics_substeps": substeps,
        "mujoco_steps_per_env_step": nstep,
        "nthread": nthread,
        "steps": steps,
        "repeats": len(times["env"]),
        "env_steps_per_s": env_sps,
        "raw_steps_per_s": raw_sps,
        "raw_sim_steps_per_s": raw_sps * nstep,
        "ratio": env_sps / raw_sps,
        "ratio_paired_median": median(paired),
        "ratio_best": min(times["raw"]) / min(times["env"]),
        "ratio_matched": t_matched / t_env,
        "ratio_matched_paired_median": median([m / e for e, m in zip(times["env"], times["matched"])]),
        "matched_ms_per_call": t_matched / steps * 1e3,
        "framework_overhead_ms": (t_env - t_matched) / steps * 1e3,
        "manager_overhead_ms": (t_env - t_raw) / steps * 1e3,
        "env_ms_per_call": t_env / steps * 1e3,
        "raw_ms_per_call": t_raw / steps * 1e3,
        "env_spread": spread(times["env"]),
        "raw_spread": spread(times["raw"]),
        "env_times_s": times["env"],
        "raw_times_s": times["raw"],
        "matched_times_s": times["matched"],
        "breakdown": parts,
    }


def _step_overhead_verdicts(records: list[dict[str, Any]]) -> list[str]:
    """One line per measured num_envs with a target in :data:`STEP_OVERHEAD_TARGETS`."""
    out = []
    for rec in records:
        target = STEP_OVERHEAD_TARGETS.get(rec["num_envs"])
        if target is None:
            continue
        marks = [
            f"{name} {rec[key]:.3f} {'meets' if rec[key] >= target else 'MISSES'}"
            for name, key in (("ratio", "ratio"), ("ratio_matched", "ratio_matched"))
        ]
        ceiling = (rec.get("breakdown") or {}).get("ceiling_ratio")
        if ceiling is not None:  # what the ratio would be if the framework's Python were free
            marks.append(f"ceiling {ceiling:.3f}{'' if ceiling >= target else ' (below the target)'}")
        out.append(f"num_envs={rec['num_envs']}: target >= {target}: " + ", ".join(marks))
    return out


def _loadavg() -> Optional[list[float]]:
    """1/5/15-minute load averages (a busy neighbour shows here), or None."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None


COLUMNS = [
    ("num_envs", "num_envs", "d"),
    ("steps", "calls", "d"),
    ("env_steps_per_s", "env steps/s", ",.0f"),
    ("raw_steps_per_s", "raw steps/s", ",.0f"),
    ("ratio", "ratio", ".3f"),
    ("env_ms_per_call", "env ms/call", ".3f"),
    ("raw_ms_per_call", "raw ms/call", ".3f"),
    ("manager_overhead_ms", "overhead ms/call", ".3f"),
    ("matched_ms_per_call", "matched raw ms/call", ".3f"),
    ("ratio_matched", "ratio matched", ".3f"),
]


def parse_args(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--num-envs", type=int, nargs="+", default=None, help="env counts (default 1 16 64 256)")
    p.add_argument(
        "--steps",
        type=int,
        default=None,
        help="env.step calls per timed run (default: sized to ~--target-seconds per run)",
    )
    p.add_argument("--repeats", type=int, default=None, help="timed runs of env and raw, interleaved (default 7)")
    p.add_argument("--sim-steps-per-control", type=int, default=4)
    p.add_argument("--episode-length", type=int, default=100, help="env steps per episode (staggered)")
    p.add_argument(
        "--target-seconds", type=float, default=0.6, help="length of one timed run when --steps is not given"
    )
    p.add_argument("--warmup-steps", type=int, default=None, help="untimed env.step calls first (default 20)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="time the runs on the wall clock, or by CPU time of this process (all threads summed: "
        "steadier on a busy box; the same as wall time of an idle box at 1 env)",
    )
    p.add_argument("--out", default=DEFAULT_OUT, help=f"JSON output (default {DEFAULT_OUT})")
    p.add_argument(
        "--quick",
        action="store_true",
        help="smoke run: num_envs 2, 5 steps, 1 repeat (structure check, not a measurement)",
    )
    p.add_argument(
        "--no-breakdown",
        dest="breakdown",
        action="store_false",
        help="skip the instrumented pass that splits env time into MuJoCo calls and Python",
    )
    p.add_argument(
        "--profile",
        action="store_true",
        help="profile env.step instead (pyinstrument if installed, else cProfile); "
        "default --num-envs 64, --steps 300; writes no JSON",
    )
    args = p.parse_args(argv)
    if args.profile:
        args.num_envs = args.num_envs or [64]
        args.steps = args.steps or 300
    if args.quick:
        args.num_envs = args.num_envs or [2]
        args.steps = args.steps or 5
        args.repeats = args.repeats or 1
        args.warmup_steps = args.warmup_steps if args.warmup_steps is not None else 2
    args.num_envs = args.num_envs or [1, 16, 64, 256]
    args.repeats = args.repeats or 7
    args.warmup_steps = args.warmup_steps if args.warmup_steps is not None else 20
    if any(n < 1 for n in args.num_envs) or args.repeats < 1 or (args.steps is not None and args.steps < 1):
        p.error("--num-envs, --steps and --repeats must be positive")
    return args


def profile(num_envs: int, sim_steps_per_control: int, steps: int, episode_length: int, seed: int = 0) -> None:
    """Print where ``env.step`` spends its time at ``num_envs``."""
    env = make_env(num_envs, sim_steps_per_control, episode_length, seed)
    run = cycling(env.step, make_actions(env))
    run(50)
    try:
        from pyinstrument import Profiler
    except ImportError:
        Profiler = None
    print(f"# profile of {steps} env.step calls, num_envs={num_envs}, sim_steps_per_control={sim_steps_per_control}")
    if Profiler is not None:
        prof = Profiler(interval=0.0001)
        prof.start()
        run(steps)
        prof.stop()
        print(prof.output_text(unicode=False, color=False, show_all=False))
    else:
        import cProfile
        import pstats

        prof = cProfile.Profile()
        prof.enable()
        run(steps)
        prof.disable()
        pstats.Stats(prof).sort_stats("cumulative").print_stats(40)
    env.close()


BREAKDOWN_COLUMNS = [
    ("num_envs", "num_envs", "d"),
    ("env_ms_per_call", "env ms/call", ".3f"),
    ("env_batch_step_ms", "Batch.step in env", ".3f"),
    ("raw_ms_per_call", "raw ms/call", ".3f"),
    ("physics_excess_ms", "physics excess", "+.3f"),
    ("env_batch_forward_ms", "forward", ".3f"),
    ("env_batch_reset_ms", "reset", ".3f"),
    ("env_python_ms", "Python", ".3f"),
    ("task_functor_ms", "of which task functors", ".3f"),
    ("framework_python_ms", "framework Python", ".3f"),
    ("ceiling_ratio", "ceiling", ".3f"),
]


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = parse_args(argv)
    torch.set_grad_enabled(False)
    if args.profile:
        for n in args.num_envs:
            profile(n, args.sim_steps_per_control, args.steps, args.episode_length, args.seed)
        return {}
    records = []
    load_before = _loadavg()
    for n in args.num_envs:
        rec = measure(
            n,
            args.sim_steps_per_control,
            args.steps,
            args.repeats,
            args.warmup_steps,
            args.target_seconds,
            args.episode_length,
            args.seed,
            args.breakdown,
            args.clock,
        )
        records.append(rec)
        print(
            f"num_envs={n:<4d} env {rec['env_steps_per_s']:>9,.0f} steps/s  raw {rec['raw_steps_per_s']:>9,.0f} "
            f"steps/s  ratio {rec['ratio']:.3f}  overhead {rec['manager_overhead_ms']:.3f} ms/call  "
            f"ratio to the matched twin {rec['ratio_matched']:.3f}",
            flush=True,
        )
    payload = {
        "benchmark": "env_throughput",
        "description": "EmbodiedEnv env-steps/s vs raw mujoco.batch.Batch stepping of the same model",
        "settings": {
            "sim_steps_per_control": args.sim_steps_per_control,
            "episode_length": args.episode_length,
            "repeats": args.repeats,
            "steps": args.steps,
            "warmup_steps": args.warmup_steps,
            "quick": bool(args.quick),
            "seed": args.seed,
            "clock": args.clock,
            "scene": "7-DoF arm + gripper, 3 dynamic cubes, kinematic table, 1 point light, no cameras",
            "managers": "2 reset events, 1 interval event, 3 observation add functors, 3 reward terms",
            "raw_batch": "persistent=True, stage=mjSTAGE_VEL, nthread=min(cpu_count, num_envs)",
            "target_ratio_at_64_envs": TARGET_RATIO_AT_64,
            "step_overhead_targets": {str(k): v for k, v in STEP_OVERHEAD_TARGETS.items()},
        },
        "machine": dict(machine_info(), loadavg_before=load_before, loadavg_after=_loadavg()),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "results": records,
    }
    print()
    print_table(
        records,
        COLUMNS,
        title=f"EmbodiedEnv vs raw Batch, sim_steps_per_control={args.sim_steps_per_control} "
        f"(median of {args.repeats} runs)",
    )
    parts = [dict(r["breakdown"], num_envs=r["num_envs"]) for r in records if r.get("breakdown")]
    if parts:
        print()
        print_table(parts, BREAKDOWN_COLUMNS, title="Where an env step goes (instrumented pass, ms per env.step call)")
    at64 = [r for r in records if r["num_envs"] == 64]
    if at64 and not args.quick:
        verdict = "meets" if at64[0]["ratio"] >= TARGET_RATIO_AT_64 else "MISSES"
        print(f"\nnum_envs=64: ratio {at64[0]['ratio']:.3f} {verdict} the target >= {TARGET_RATIO_AT_64}")
    if not args.quick:
        for line in _step_overhead_verdicts(records):
            print(line)
    if args.out:
        print(f"wrote {write_json(args.out, payload)}")
    return payload


if __name__ == "__main__":
    main()
