"""Cost of domain randomization on reset: a reset with 10 randomization events against
a plain reset, at 64 envs (target: <= 1 ms extra).

The scene: the 7-DoF arm with a gripper, two dynamic cubes, a kinematic table and a
point light, no cameras. The randomized env adds 10 ``reset`` events from
embodichain-functors (poses of both cubes, arm joints, cube mass, centre of mass and
friction, arm joint damping, light position/colour/intensity, table colour, a
virtual target pose); the plain env has none. Both reset all envs; resets of the
two are interleaved ``--repeats`` times after a warm-up and medians are reported.

A second pass times each event alone (called by its manager entry for all envs)
and counts MuJoCo's ``mj_setConst`` batch calls, the part of a physics
randomization that recomputes derived model constants (masses, frames).

``--proposed-core`` adds a row measured with two core changes proposed in
docs/functors.md, applied in-process to this benchmark only: a vectorized
``Light`` colour write, and ``mj_setConst`` deferred to once per reset (run
before the next forward/step/render) instead of once per written field.

Usage:
    python benchmarks/reset_randomization.py [--num-envs 64] [--repeats 15] [--proposed-core]
        [--cpu-num 0] [--out benchmarks/results/reset_randomization.json] [--quick]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import torch  # noqa: E402

from common import interleaved_timings, machine_info, median, print_table, seven_dof_arm_mjcf, spread, write_json  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402
from embodichain_core.managers import EventCfg  # noqa: E402
from embodichain_core.managers import SceneEntityCfg as E  # noqa: E402
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.shapes import CubeCfg  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "reset_randomization.json")
TARGET_EXTRA_MS = 1.0


def randomization_events() -> dict[str, EventCfg]:
    """The 10 reset events of the randomized env."""
    import embodichain_functors.randomization as rand

    def ev(func: Any, **params: Any) -> EventCfg:
        return EventCfg(func=func, mode="reset", params=params)

    xy = [[-0.1, -0.1, 0.0], [0.1, 0.1, 0.0]]
    return {
        "cube0_pose": ev(rand.randomize_rigid_object_pose, entity_cfg=E(uid="cube0"), position_range=xy,
                         rotation_range=[[0, 0, -180], [0, 0, 180]]),
        "cube1_pose": ev(rand.randomize_rigid_object_pose, entity_cfg=E(uid="cube1"), position_range=xy),
        "arm_qpos": ev(rand.randomize_robot_qpos, entity_cfg=E(uid="arm", joint_names=["joint[1-7]"]),
                       qpos_range=[-0.1, 0.1]),
        "cube0_mass": ev(rand.randomize_rigid_object_mass, entity_cfg=E(uid="cube0"), mass_range=[0.05, 0.5]),
        "cube1_com": ev(rand.randomize_rigid_object_center_of_mass, entity_cfg=E(uid="cube1"),
                        com_pos_offset_range=[[-0.01, -0.01, 0.0], [0.01, 0.01, 0.0]]),
        "cube0_friction": ev(rand.randomize_rigid_object_friction, entity_cfg=E(uid="cube0"),
                             friction_range=[0.4, 1.2]),
        "arm_damping": ev(rand.randomize_joint_damping, entity_cfg=E(uid="arm"), damping_range=[0.0, 0.5]),
        "light": ev(rand.randomize_light, entity_cfg=E(uid="lamp"), position_range=[[-0.5, -0.5, 0], [0.5, 0.5, 0]],
                    color_range=[[0.6, 0.6, 0.6], [1.0, 1.0, 1.0]], intensity_range=[-10.0, 10.0]),
        "table_colour": ev(rand.randomize_visual_material, entity_cfg=E(uid="table"),
                           base_color_range=[[0.2, 0.2, 0.2], [1.0, 1.0, 1.0]]),
        "target": ev(rand.randomize_target_pose, position_range=[[0.3, -0.2, 0.35], [0.6, 0.2, 0.35]],
                     store_key="goal_pose"),
    }


CPU_NUM = 0  # batch threads (0: one per core, up to num_envs); --cpu-num sets it


def make_env(num_envs: int, randomized: bool) -> EmbodiedEnv:
    cubes = [RigidObjectCfg(uid=f"cube{k}", shape=CubeCfg(size=[0.05, 0.05, 0.05]), init_pos=(0.5, 0.15 * k - 0.1, 0.345))
             for k in range(2)]
    cfg = EmbodiedEnvCfg(
        num_envs=num_envs, seed=0, verbose=False, max_episode_steps=100,
        robot=RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]}),
        control_parts=["arm"], rigid_object=cubes,
        background=[RigidObjectCfg(uid="table", shape=CubeCfg(size=[0.6, 0.9, 0.32]), init_pos=(0.6, 0.0, 0.16),
                                   body_type="kinematic")],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="lamp", init_pos=(1.0, 0.0, 2.0))]),
        events=randomization_events() if randomized else {},
    )
    cfg.sim_cfg.cpu_num = CPU_NUM
    return EmbodiedEnv(cfg)


class SetConstCounter:
    """Counts and times ``Batch.set_const`` calls of one env (measurement only)."""

    def __init__(self, env: EmbodiedEnv):
        self.calls, self.seconds = 0, 0.0
        batch = env.sim.batch
        original = batch.set_const

        def counted(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.calls += 1
                self.seconds += time.perf_counter() - start

        batch.set_const = counted


class DeferredSetConst:
    """The proposed core change, in-process: ``Batch.set_const`` calls are collected and
    run once, before the simulation is next read, stepped or rendered (measurement only)."""

    def __init__(self, env: EmbodiedEnv):
        import numpy as np

        sim, self.pending = env.sim, None
        batch, original = sim.batch, sim.batch.set_const

        def defer(ids: Any = None) -> None:
            ids = np.arange(sim.num_envs) if ids is None else np.asarray(ids)
            self.pending = ids if self.pending is None else np.union1d(self.pending, ids)

        def flush() -> None:
            if self.pending is not None:
                ids, self.pending = self.pending, None
                original(None if len(ids) == sim.num_envs else ids.astype(np.int32))

        batch.set_const = defer
        for name in ("forward", "step", "get_model", "get_data"):
            method = getattr(sim, name)
            setattr(sim, name, lambda *a, _m=method, **k: (flush(), _m(*a, **k))[1])


def vectorize_light_colour(env: EmbodiedEnv) -> None:
    """The proposed core change, in-process for ``env``'s lights: ``Light`` writes its
    diffuse colour for all envs at once instead of one env at a time (measurement only)."""
    import types

    def write_diffuse(self: Any, ids: torch.Tensor) -> None:
        self._touched = True
        scale = (self._intensity[ids] / 30.0).clamp(0.0, 1.0)[:, None]
        self.sim.set_model_field("light_diffuse", ids, self.light_id, (self._color[ids] * scale).clamp(0.0, 1.0).numpy())
        self.sim.set_model_field("light_intensity", ids, self.light_id, self._intensity[ids].numpy())

    for light in env.scene.lights.values():
        light._write_diffuse = types.MethodType(write_diffuse, light)


def per_event(env: EmbodiedEnv, repeats: int, counter: SetConstCounter) -> list[dict[str, Any]]:
    """Median time of each event alone for every env, and its mj_setConst calls."""
    ids = torch.arange(env.num_envs)
    rows = []
    for name, entry in env.event_manager.entries.items():
        entry(env, ids)  # warm-up (and the one-time param checks)
        calls = counter.calls
        times = [_time(lambda: entry(env, ids)) for _ in range(repeats)]
        rows.append({"event": name, "functor": entry.cfg.func.__name__, "ms": 1e3 * median(times),
                     "set_const_calls": (counter.calls - calls) // repeats})
    return rows


def _time(fn: Any) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _record(name: str, num_envs: int, plain: list[float], randomized: list[float], counter: SetConstCounter,
            env: EmbodiedEnv) -> dict[str, Any]:
    counter.calls, counter.seconds = 0, 0.0
    env.reset()
    t_plain, t_rand = median(plain), median(randomized)
    return {
        "core": name, "num_envs": num_envs, "events": len(env.event_manager.entries), "repeats": len(plain),
        "plain_reset_ms": 1e3 * t_plain, "randomized_reset_ms": 1e3 * t_rand, "extra_ms": 1e3 * (t_rand - t_plain),
        "target_extra_ms": TARGET_EXTRA_MS, "meets_target": (t_rand - t_plain) * 1e3 <= TARGET_EXTRA_MS,
        "set_const_calls_per_reset": counter.calls, "set_const_ms_per_reset": 1e3 * counter.seconds,
        "spread_plain": spread(plain), "spread_randomized": spread(randomized),
        "load_average_1min": os.getloadavg()[0],
    }


def measure(num_envs: int, repeats: int, proposed: bool = False) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Records (as is, and with the proposed core changes) and the per-event rows.

    All contenders are reset in interleaved rounds, so background load hits them alike.
    """
    envs = {"plain": make_env(num_envs, False), "randomized": make_env(num_envs, True)}
    if proposed:
        envs.update({"plain+": make_env(num_envs, False), "randomized+": make_env(num_envs, True)})
    counters = {name: SetConstCounter(env) for name, env in envs.items() if name.startswith("randomized")}
    for name in ("plain+", "randomized+"):
        if name in envs:
            vectorize_light_colour(envs[name])
            DeferredSetConst(envs[name])
    try:
        timings = interleaved_timings({name: env.reset for name, env in envs.items()}, repeats, warmup=3)
        records = [_record("as is", num_envs, timings["plain"], timings["randomized"], counters["randomized"],
                           envs["randomized"])]
        if proposed:
            records.append(_record("with proposed changes", num_envs, timings["plain+"], timings["randomized+"],
                                   counters["randomized+"], envs["randomized+"]))
        return records, per_event(envs["randomized"], max(3, repeats // 3), counters["randomized"])
    finally:
        for env in envs.values():
            env.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--num-envs", type=int, nargs="+", default=[64])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--out", default=DEFAULT_OUT, help="JSON output ('' writes none)")
    parser.add_argument("--quick", action="store_true", help="2 envs, 2 repeats: checks the script runs")
    parser.add_argument("--cpu-num", type=int, default=0, help="simulation threads (0: one per core)")
    parser.add_argument("--proposed-core", action="store_true",
                        help="also measure with the proposed core changes (patched in-process)")
    args = parser.parse_args(argv)
    if args.quick:
        args.num_envs, args.repeats = [2], 2
    global CPU_NUM
    CPU_NUM = args.cpu_num
    records, events = [], {}
    for n in args.num_envs:
        rows, events[str(n)] = measure(n, args.repeats, args.proposed_core)
        records += rows
    print_table(records, [("core", "core", "s"), ("num_envs", "envs", "d"), ("plain_reset_ms", "plain reset ms", ".3f"),
                          ("randomized_reset_ms", "10 events ms", ".3f"), ("extra_ms", "extra ms", ".3f"),
                          ("set_const_calls_per_reset", "mj_setConst calls", "d"),
                          ("set_const_ms_per_reset", "mj_setConst ms", ".3f")],
                title=f"Reset with 10 randomization events vs a plain reset (target: <= {TARGET_EXTRA_MS} ms extra)")
    for n, rows in events.items():
        print_table(rows, [("event", "event", "s"), ("functor", "functor", "s"), ("ms", "ms", ".3f"),
                           ("set_const_calls", "mj_setConst calls", "d")], title=f"\nEach event alone, {n} envs")
    if args.out:
        path = write_json(args.out, {"benchmark": "reset_randomization", "machine": machine_info(),
                                     "cpu_num": args.cpu_num,
                                     "records": records, "per_event": events})
        print(f"\nwrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
