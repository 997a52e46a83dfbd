"""Recorded env-steps/s with a 128x128 stereo camera: synchronous vs asynchronous
LeRobot recorder vs stepping without recording, in one run.

The env: the 7-DoF arm (7 active joints), a cube, a point light and a 128x128
stereo camera (colour; ``--depth`` adds depth maps), 25 Hz control. Every episode
succeeds at ``--episode-length`` steps and is auto-reset, so the dataset manager
commits it (episode ends are staggered across envs as in real data generation).
Three envs are built with identical configs: ``none`` (no dataset section),
``sync`` (``LeRobotRecorder``) and ``async`` (``AsyncLeRobotRecorder``), for
each storage mode (``video``: AV1 mp4, ``image``: PNG in parquet).

Each round steps every contender ``--steps`` times (interleaved; medians over
``--repeats`` rounds after a warm-up round). Reported per contender:

* ``env_steps_per_s``: what the stepping loop sees (``steps * num_envs / t``);
* ``end_to_end_steps_per_s``: also waiting until every committed episode is
  written (the async queue drained) at the end of the round;
* ``ratio``: ``env_steps_per_s`` over the ``none`` contender's.

The ``main_job`` case (:mod:`record_main_job`) runs ``make run``'s config recorded and
unrecorded (``--filter_dataset_saving``), each in its own process, and reports the
end-to-end ratio (the final flush included) and the build times; ``main_job_depth_masks``
records it with and without the camera's depth and masks and reports the size ratio and
the ``embodichain dataset preview`` times.

Needs embodichain-sensors and embodichain-lerobot (lerobot 0.4.x); the main job case
also embodichain-tasks.

Usage:
    python benchmarks/record_throughput.py [--case stereo main_job] [--num-envs 1 4]
        [--storage video image] [--steps 150] [--episode-length 50] [--repeats 3]
        [--main-job-episodes 4] [--out benchmarks/results/record_throughput.json] [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import sys
import tempfile
import time
from typing import Any, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")
os.environ.setdefault("SVT_LOG", "1")

import embodichain_core.sim  # noqa: E402,F401  (chooses MUJOCO_GL before mujoco is imported)
import torch  # noqa: E402

from common import machine_info, median, print_table, seven_dof_arm_mjcf, spread, write_json  # noqa: E402
from record_main_job import measure_depth_masks, measure_main_job  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402
from embodichain_core.managers import DatasetFunctorCfg  # noqa: E402
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.shapes import CubeCfg  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "record_throughput.json")
CONTENDERS = {"none": None, "sync": "LeRobotRecorder", "async": "AsyncLeRobotRecorder"}


class TimedDemoEnv(EmbodiedEnv):
    """Every episode succeeds when it reaches ``episode_length`` steps."""

    episode_length = 50

    def compute_task_state(self, **kwargs: Any) -> tuple:
        success = self.elapsed_steps >= self.episode_length
        return success, torch.zeros_like(success), {}


def make_cfg(
    num_envs: int,
    func: Optional[str],
    save_path: str,
    storage: str,
    size: tuple[int, int],
    depth: bool,
    episode_length: int,
) -> EmbodiedEnvCfg:
    """The benchmark env: arm, cube, light, stereo camera; a recorder unless ``func`` is None.

    ``max_episode_steps`` stays just above the episode length (the episodes end by success).
    """
    from embodichain_sensors.cfg import StereoCameraCfg

    w, h = size
    cam = StereoCameraCfg(
        uid="head",
        width=w,
        height=h,
        intrinsics=(w, w, w / 2, h / 2),
        enable_depth=depth,
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(eye=(1.4, 0.0, 1.1), target=(0.2, 0.0, 0.3)),
    )
    dataset = (
        None
        if func is None
        else {
            "rec": DatasetFunctorCfg(
                func=func,
                params={
                    "save_path": save_path,
                    "robot_meta": {"robot_type": "arm7"},
                    "instruction": {"lang": "reach"},
                    "extra": {"scene_type": "bench"},
                    "use_videos": storage == "video",
                },
            )
        }
    )
    return EmbodiedEnvCfg(
        num_envs=num_envs,
        seed=0,
        verbose=False,
        max_episode_steps=episode_length + 1,
        robot=RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]}),
        control_parts=["arm"],
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05] * 3), init_pos=(0.5, 0.0, 0.025))],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0))]),
        sensor=[cam],
        dataset=dataset,
    )


def make_env(cfg: EmbodiedEnvCfg, episode_length: int) -> EmbodiedEnv:
    env = TimedDemoEnv(cfg)
    env.episode_length = episode_length
    env.reset(seed=0)
    n = env.num_envs
    env._elapsed_steps[:] = (torch.arange(n) * episode_length // max(1, n)).to(env._elapsed_steps.dtype)
    return env


def actions(n: int, period: int = 40) -> list[torch.Tensor]:
    phase = torch.linspace(0, 2 * math.pi, n + 1)[:n, None] + torch.arange(7)[None, :] * 0.7
    return [(0.4 * torch.sin(phase + 2 * math.pi * k / period)).float() for k in range(period)]


class Contender:
    """One env and its stepping loop."""

    def __init__(self, name: str, env: EmbodiedEnv):
        self.name, self.env = name, env
        self.rec = env.dataset_manager.get_functor("rec") if env.dataset_manager is not None else None
        self.actions, self.k = actions(env.num_envs), 0
        self.step_s: list[float] = []
        self.total_s: list[float] = []

    def round(self, steps: int) -> None:
        start = time.perf_counter()
        for _ in range(steps):
            self.env.step(self.actions[self.k % len(self.actions)])
            self.k += 1
        stepped = time.perf_counter()
        if self.rec is not None and hasattr(self.rec, "wait"):
            self.rec.wait()
        self.step_s.append(stepped - start)
        self.total_s.append(time.perf_counter() - start)


def measure(
    num_envs: int,
    storage: str,
    steps: int,
    episode_length: int,
    repeats: int,
    size: tuple[int, int],
    depth: bool,
    workdir: str,
) -> dict[str, Any]:
    """One (num_envs, storage) configuration: every contender, interleaved rounds."""
    contenders = [
        Contender(
            name,
            make_env(
                make_cfg(num_envs, func, os.path.join(workdir, name), storage, size, depth, episode_length),
                episode_length,
            ),
        )
        for name, func in CONTENDERS.items()
    ]
    for c in contenders:  # warm-up: first commits create the datasets, codecs start
        c.round(min(steps, episode_length + 1))
        c.step_s.clear(), c.total_s.clear()
    for _ in range(max(1, repeats)):
        for c in contenders:
            c.round(steps)
    record: dict[str, Any] = {
        "num_envs": num_envs,
        "storage": storage,
        "steps": steps,
        "episode_length": episode_length,
        "repeats": repeats,
        "contenders": {},
    }
    base = None
    for c in contenders:
        t_step, t_total = median(c.step_s), median(c.total_s)
        sps = steps * num_envs / t_step
        base = sps if base is None else base
        record["contenders"][c.name] = {
            "env_steps_per_s": sps,
            "end_to_end_steps_per_s": steps * num_envs / t_total,
            "ratio": sps / base,
            "spread": spread(c.step_s),
            "step_times_s": c.step_s,
            "total_times_s": c.total_s,
            "episodes_saved": c.rec.saved_episodes if c.rec is not None else None,
        }
        c.env.close()
    return record


def rows(results: list[dict]) -> list[dict]:
    out = []
    for r in results:
        for name, c in r["contenders"].items():
            out.append({"storage": r["storage"], "num_envs": r["num_envs"], "recorder": name, **c})
    return out


def parse_args(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--case",
        nargs="+",
        choices=("stereo", "main_job", "main_job_depth_masks"),
        default=["stereo", "main_job", "main_job_depth_masks"],
        help="stereo: the 128x128 stereo env; main_job: make run's config (each twin in a process); "
        "main_job_depth_masks: dataset size with depth and masks, preview times",
    )
    p.add_argument("--main-job-episodes", type=int, default=4, help="saved episodes per main job run")
    p.add_argument("--num-envs", type=int, nargs="+", default=[1, 4])
    p.add_argument("--storage", nargs="+", choices=("video", "image"), default=["video", "image"])
    p.add_argument("--steps", type=int, default=150, help="env.step calls per contender per round")
    p.add_argument("--episode-length", type=int, default=50)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--size", type=int, nargs=2, default=[128, 128], metavar=("W", "H"))
    p.add_argument("--depth", action="store_true", help="also record the depth maps")
    p.add_argument("--out", default=DEFAULT_OUT, help="JSON output ('' writes none)")
    p.add_argument("--quick", action="store_true", help="1 env, 12 steps, 1 round: checks the script runs")
    args = p.parse_args(argv)
    if args.quick:
        args.num_envs, args.steps, args.episode_length, args.repeats = [1], 12, 5, 1
        args.main_job_episodes = 2
    return args


def main(argv: Optional[list[str]] = None) -> int:
    args = parse_args(argv)
    workdir = tempfile.mkdtemp(prefix="record_throughput_")
    results = []
    try:
        for storage in args.storage if "stereo" in args.case else ():
            for n in args.num_envs:
                results.append(
                    measure(
                        n, storage, args.steps, args.episode_length, args.repeats, tuple(args.size), args.depth, workdir
                    )
                )
                print_table(
                    rows(results[-1:]),
                    [
                        ("storage", "storage", ""),
                        ("num_envs", "envs", "d"),
                        ("recorder", "recorder", ""),
                        ("env_steps_per_s", "steps/s", ".1f"),
                        ("end_to_end_steps_per_s", "end-to-end/s", ".1f"),
                        ("ratio", "vs none", ".2f"),
                        ("episodes_saved", "episodes", ""),
                    ],
                )
        if "main_job" in args.case:
            results.append(measure_main_job(args.main_job_episodes, args.repeats, workdir))
            print_table(
                [{"twin": k, **v} for k, v in results[-1]["contenders"].items()],
                [
                    ("twin", "main job", ""),
                    ("build_s", "build s", ".2f"),
                    ("env_steps_per_s", "steps/s", ".1f"),
                    ("end_to_end_steps_per_s", "end-to-end/s", ".1f"),
                    ("ratio", "vs unrecorded", ".2f"),
                    ("episodes_saved", "episodes", ""),
                ],
            )
        if "main_job_depth_masks" in args.case:
            results.append(measure_depth_masks(min(2, args.main_job_episodes), workdir))
            print_table(
                results[-1:],
                [
                    ("bytes_without", "bytes without", "d"),
                    ("bytes_with", "with depth+masks", "d"),
                    ("size_ratio", "ratio", ".2f"),
                    ("size_ratio_libsvtav1", "ratio, AV1 colour", ".2f"),
                    ("preview_png_s", "preview png s", ".2f"),
                    ("preview_mp4_s", "preview mp4 s", ".2f"),
                ],
            )
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    settings = {k: v for k, v in vars(args).items() if k != "out"}
    settings["camera"] = f"stereo {args.size[0]}x{args.size[1]} colour" + (" + depth" if args.depth else "")
    import resource

    machine = {**machine_info(), "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
    payload = {"benchmark": "record_throughput", "settings": settings, "machine": machine, "results": results}
    if args.out:
        print("wrote", write_json(args.out, payload))
    return 0


if __name__ == "__main__":
    sys.exit(main())
