"""The core's demo scene as an ``EmbodiedEnv`` against the env a plain gymnasium user writes.

Every contender runs the SAME compiled model (``env.unwrapped.scene.model`` of the
demo scene: the 7-joint arm with its gripper, a kinematic table, 3 cubes, a light),
the same 20 MuJoCo steps per env step, and random joint-position targets drawn once
from the env's action space and cycled:

* ``ours``: :class:`~embodichain_core.envs.EmbodiedEnv` on the demo config, no managers
  (same-step autoreset at the 100-step episode limit);
* ``sync`` / ``async``: a ``gymnasium.envs.mujoco.MujocoEnv`` subclass (:class:`ArmMujocoEnv`,
  loading the model from an MJB file written from the env's model; observation
  ``qpos`` + ``qvel``, a control-cost reward, a 100-step ``TimeLimit``) in
  ``gymnasium.vector.SyncVectorEnv`` / ``AsyncVectorEnv`` (same-step autoreset, as ours);
* ``raw``: ``mujoco.batch.Batch`` with the backend's settings, writing ``ctrl`` and
  stepping, the least any batched env can do (back to the start every 100 steps).

All of them start every episode from our env's reset state and get the same action
sequence, so their physics (contacts, solver work) is alike.

The contenders run in interleaved rounds after a warm-up; medians are reported.
``ours / x`` is the ratio of env-steps/s (above 1: ours is faster). ``--clock cpu`` times
the CPU time of this process instead of the wall clock (steadier on a shared box; the
async contender, whose work runs in other processes, is then left out). ``--split`` adds
a pass that times, for ``ours`` and ``sync``, this thread's CPU time per env step outside
the physics call (``Batch.step``; ``MujocoEnv._step_mujoco_simulation``): what each adds
between physics calls, in the loop.

Usage:
    python benchmarks/gym_compare.py [--num-envs 1 16 64] [--repeats 5] [--async-max 16]
        [--split] [--out benchmarks/results/gym_compare.json] [--quick]
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
import tempfile
import time
from typing import Any, Callable, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import gymnasium as gym  # noqa: E402
import mujoco  # noqa: E402
import mujoco.batch as mjbatch  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402
from gymnasium.envs.mujoco import MujocoEnv  # noqa: E402

from common import cycling, interleaved_timings, machine_info, median, print_table, spread, write_json  # noqa: E402

from embodichain_core.demo import demo_cfg  # noqa: E402
from embodichain_core.envs import EmbodiedEnv  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "gym_compare.json")
EPISODE = 100
N_ACTIONS = 64  # distinct random actions, cycled


class ArmMujocoEnv(MujocoEnv):
    """What a gymnasium + MuJoCo user writes for the demo scene: ``MujocoEnv`` on a model file.

    Args:
        model_path: an MJB file of the compiled scene.
        frame_skip: MuJoCo steps per env step.
        ctrl_ids: the position actuators the action drives (one per action value).
        low, high: action bounds (the joint ranges).
        init_qpos: where each episode starts.
    """

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(
        self,
        model_path: str,
        frame_skip: int,
        ctrl_ids: list[int],
        low: np.ndarray,
        high: np.ndarray,
        init_qpos: np.ndarray,
    ):
        self._ctrl_ids = np.asarray(ctrl_ids, dtype=np.int64)
        super().__init__(model_path, frame_skip, observation_space=None, width=64, height=64)
        self.init_qpos = np.array(init_qpos, dtype=np.float64)  # the start of our env's episodes
        size = self.model.nq + self.model.nv
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (size,), np.float64)
        self.action_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        self._ctrl = np.zeros(self.model.nu)

    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        model = mujoco.MjModel.from_binary_path(self.fullpath)
        return model, mujoco.MjData(model)

    def _obs(self) -> np.ndarray:
        return np.concatenate((self.data.qpos, self.data.qvel))

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        self._ctrl[self._ctrl_ids] = action
        self.do_simulation(self._ctrl, self.frame_skip)
        reward = -1e-3 * float(np.square(action).sum())
        return self._obs(), reward, False, False, {}

    def reset_model(self) -> np.ndarray:
        self.set_state(self.init_qpos, self.init_qvel)
        return self._obs()


def make_ours(num_envs: int, seed: int = 0) -> EmbodiedEnv:
    """The demo scene with ``num_envs`` envs, no managers, quiet."""
    cfg = demo_cfg()
    cfg.verbose = False
    cfg.max_episode_steps = EPISODE
    env = EmbodiedEnv(cfg, num_envs=num_envs)
    env.reset(seed=seed)
    return env


def gym_factory(env: EmbodiedEnv, folder: str) -> Callable[[], gym.Env]:
    """A picklable constructor of :class:`ArmMujocoEnv` on ``env``'s compiled model (as MJB)."""
    path = os.path.join(folder, "demo_scene.mjb")
    mujoco.mj_saveModel(env.scene.model, path, None)
    robot, aid = env.robot, torch.as_tensor(env.active_joint_ids)
    low, high = env.single_action_space.low, env.single_action_space.high
    frame_skip = env.sim_steps_per_control * env.sim.substeps
    init_qpos = env.sim.qpos[0].numpy().copy()
    return functools.partial(_limited_env, path, frame_skip, robot.pos_act[aid].tolist(), low, high, init_qpos)


def _limited_env(*args: Any) -> gym.Env:
    return gym.wrappers.TimeLimit(ArmMujocoEnv(*args), EPISODE)


def random_actions(env: EmbodiedEnv, num_envs: int, seed: int) -> np.ndarray:
    """``(N_ACTIONS, num_envs, dim)`` float32 uniform samples of the action space."""
    rng = np.random.default_rng(seed)
    low, high = env.single_action_space.low, env.single_action_space.high
    return rng.uniform(low, high, (N_ACTIONS, num_envs, len(low))).astype(np.float32)


def contenders(num_envs: int, with_async: bool, folder: str, seed: int = 0) -> tuple[dict, list[Callable], dict]:
    """``{name: run(n_steps)}`` for one ``num_envs``, the closers, and ``{"ours", "sync"}``'s envs."""
    ours = make_ours(num_envs, seed)
    acts_np = random_actions(ours, num_envs, seed)
    acts_t = [torch.from_numpy(a) for a in acts_np]
    make = gym_factory(ours, folder)
    sync = gym.vector.SyncVectorEnv([make] * num_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP)
    sync.reset(seed=seed)
    runs: dict[str, Callable[[int], None]] = {"ours": cycling(ours.step, acts_t), "sync": cycling(sync.step, acts_np)}
    closers: list[Callable] = [ours.close, sync.close]
    if with_async:
        async_env = gym.vector.AsyncVectorEnv([make] * num_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP)
        async_env.reset(seed=seed)
        runs["async"] = cycling(async_env.step, acts_np)
        closers.append(async_env.close)
    runs["raw"] = _raw_loop(ours, acts_np)
    return runs, closers, {"ours": ours, "sync": sync}


def _raw_loop(env: EmbodiedEnv, actions: np.ndarray) -> Callable[[int], None]:
    """``Batch.step`` of the same model with the backend's settings, from the env's reset
    state, back to it every ``EPISODE`` steps."""
    n = env.num_envs
    batch = mjbatch.Batch(env.scene.model, n, nthread=min(os.cpu_count() or 1, n), persistent=True)
    batch.reset(None)
    start = env.sim.state.copy()
    ctrl = batch.bind("ctrl")
    cols = env.robot.pos_act[torch.as_tensor(env.active_joint_ids)].numpy()
    nstep, stage = env.sim_steps_per_control * env.sim.substeps, mujoco.mjtStage.mjSTAGE_VEL
    state = {"t": 0}

    def step(action: np.ndarray) -> None:
        if state["t"] % EPISODE == 0:
            batch.state[...] = start
            batch.forward(None, stage=stage)
        state["t"] += 1
        ctrl[:, cols] = action
        batch.step(nstep=nstep, stage=stage)

    return cycling(step, list(actions.astype(np.float64)))


def outside_physics(runs: dict, envs: dict, steps: int, repeats: int) -> dict[str, float]:
    """``{"ours", "sync"}``: median CPU time (this thread, µs) per env step outside the physics
    call, from interleaved rounds with that call timed (``MujocoEnv`` steps include their
    ``mj_rnePostConstraint``)."""
    spent = {"ours": 0, "sync": 0}

    def timed(name: str, call: Callable) -> Callable:
        def run(*args: Any, **kwargs: Any) -> Any:
            start = time.thread_time_ns()
            try:
                return call(*args, **kwargs)
            finally:
                spent[name] += time.thread_time_ns() - start

        return run

    batch = envs["ours"].sim.batch  # the backend's mujoco.batch.Batch: an instance attribute shadows its step
    inners = [e.unwrapped for e in envs["sync"].envs]
    batch.step = timed("ours", batch.step)
    for inner in inners:
        inner._step_mujoco_simulation = timed("sync", inner._step_mujoco_simulation)
    out: dict[str, list[float]] = {"ours": [], "sync": []}
    try:
        for _ in range(max(1, repeats)):
            for name in out:
                spent[name] = 0
                start = time.thread_time_ns()
                runs[name](steps)
                out[name].append((time.thread_time_ns() - start - spent[name]) / steps / 1e3)
    finally:
        del batch.step
        for inner in inners:
            del inner._step_mujoco_simulation
    return {name: median(values) for name, values in out.items()}


def measure(
    num_envs: int,
    steps: Optional[int],
    repeats: int,
    target_seconds: float,
    with_async: bool,
    seed: int = 0,
    clock: str = "wall",
    split: bool = False,
) -> dict[str, Any]:
    """One ``num_envs``: every contender timed in interleaved rounds; the JSON record."""
    outside: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder:
        runs, closers, envs = contenders(num_envs, with_async, folder, seed)
        try:
            for run in runs.values():  # warm-up, and the slowest per-call time sizes the runs
                run(5)
            if steps is None:
                per_call = max(_seconds(lambda r=run: r(10)) / 10 for run in runs.values())
                steps = int(min(5000, max(10, round(target_seconds / max(per_call, 1e-6)))))
            times = interleaved_timings(
                {k: functools.partial(r, steps) for k, r in runs.items()}, repeats, warmup=0, clock=clock
            )
            if split:
                outside = outside_physics(runs, envs, steps, repeats)
        finally:
            for close in closers:
                close()
    rate = {k: steps * num_envs / median(v) for k, v in times.items()}
    rec: dict[str, Any] = {"num_envs": num_envs, "steps": steps, "repeats": repeats}
    for name in ("ours", "raw", "sync", "async"):
        rec[f"{name}_steps_per_s"] = rate.get(name)
        rec[f"{name}_spread"] = spread(times[name]) if name in times else None
        rec[f"{name}_times_s"] = times.get(name)
    for name in ("raw", "sync", "async"):
        rec[f"ours_over_{name}"] = rate["ours"] / rate[name] if name in rate else None
    for name in ("ours", "sync"):
        rec[f"{name}_outside_physics_us"] = outside.get(name)
    return rec


def _seconds(fn: Callable[[], Any]) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


COLUMNS = [
    ("num_envs", "num_envs", "d"),
    ("ours_steps_per_s", "ours steps/s", ",.0f"),
    ("raw_steps_per_s", "raw Batch", ",.0f"),
    ("sync_steps_per_s", "gym Sync", ",.0f"),
    ("async_steps_per_s", "gym Async", ",.0f"),
    ("ours_over_raw", "ours / raw", ".2f"),
    ("ours_over_sync", "ours / Sync", ".2f"),
    ("ours_over_async", "ours / Async", ".2f"),
    ("ours_outside_physics_us", "ours µs outside physics", ".1f"),
    ("sync_outside_physics_us", "Sync µs outside physics", ".1f"),
]


def parse_args(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--num-envs", type=int, nargs="+", default=None, help="env counts (default 1 16 64)")
    p.add_argument("--steps", type=int, default=None, help="env steps per timed run (default: ~--target-seconds)")
    p.add_argument("--repeats", type=int, default=5, help="interleaved rounds; medians are reported")
    p.add_argument("--target-seconds", type=float, default=0.4, help="length of one timed run without --steps")
    p.add_argument(
        "--async-max",
        type=int,
        default=16,
        help="largest num_envs run in AsyncVectorEnv (one process per env; 0: never)",
    )
    p.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="wall clock, or CPU time of this process (all threads; no async contender)",
    )
    p.add_argument(
        "--split",
        action="store_true",
        help="also time ours' and Sync's CPU time per step outside the physics call (this thread)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=DEFAULT_OUT, help=f"JSON output ('' writes none; default {DEFAULT_OUT})")
    p.add_argument("--quick", action="store_true", help="smoke run: 1 and 2 envs, 3 steps, 1 round (not a measurement)")
    args = p.parse_args(argv)
    if args.quick:
        args.num_envs, args.steps, args.repeats = args.num_envs or [1, 2], args.steps or 3, 1
    args.num_envs = args.num_envs or [1, 16, 64]
    if any(n < 1 for n in args.num_envs) or args.repeats < 1 or (args.steps is not None and args.steps < 1):
        p.error("--num-envs, --steps and --repeats must be positive")
    return args


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = parse_args(argv)
    torch.set_grad_enabled(False)
    load_before = os.getloadavg()
    records = []
    for n in args.num_envs:
        with_async = n <= args.async_max and args.clock == "wall"
        rec = measure(n, args.steps, args.repeats, args.target_seconds, with_async, args.seed, args.clock, args.split)
        records.append(rec)
        print(
            f"num_envs={n:<3d} ours/raw {rec['ours_over_raw']:.2f}  ours/Sync {rec['ours_over_sync']:.2f}", flush=True
        )
    payload = {
        "benchmark": "gym_compare",
        "description": "EmbodiedEnv (demo scene, no managers) vs a gymnasium MujocoEnv in Sync/AsyncVectorEnv "
        "and raw mujoco.batch, same compiled model, 20 MuJoCo steps per env step",
        "settings": {
            "repeats": args.repeats,
            "steps": args.steps,
            "episode_length": EPISODE,
            "clock": args.clock,
            "async_max": args.async_max,
            "split": bool(args.split),
            "quick": bool(args.quick),
            "seed": args.seed,
        },
        "machine": dict(machine_info(), loadavg_before=list(load_before), loadavg_after=list(os.getloadavg())),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "results": records,
    }
    print()
    print_table(
        records,
        COLUMNS,
        title=f"Demo scene, env-steps/s (median of {args.repeats} interleaved rounds, {args.clock} clock)",
    )
    if args.out:
        print(f"wrote {write_json(args.out, payload)}")
    return payload


if __name__ == "__main__":
    main()
