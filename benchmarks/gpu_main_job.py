"""The data-generation job on backend ``warp``: recorded env-steps/s end to end, with the time per phase.

``--case main_job`` (default): PickFork-v1 as ``embodichain_tasks/configs/main_job.json``
configures it (the W1 robot, its 320x180 stereo head camera, the fork's mesh, mass and pose,
the light and the table material randomized per episode, the scripted demonstration, the
``AsyncLeRobotRecorder`` with h264 videos), on backend ``warp`` and ``--device``, at each
``--num-envs`` (``--episodes-per-env`` episodes each). The recorded rate counts what reached
disk: the frames of the episodes the dataset holds once finalized, loaded back with
lerobot, over the wall time of the run plus the final flush. Phases (seconds, each call
between two device syncs):

* ``physics``: ``sim.advance`` (every env step's physics);
* ``render``: the camera updates;
* ``demo_ik``: planning the scripted demonstrations (their IK included);
* ``device_to_host``: the recorder's per-step call (frames and state copied off the device
  and queued to the writer);
* ``encoding_writing``: the CPU seconds of the writer process and the recorder's encoder
  processes (video encoding, parquet), and ``flush``: the wall time of the final flush.

``--encoder-processes`` sets the recorder's ``encoder_processes`` (default: the job's config,
``"auto"``: one encoder process per two cores beyond two, see docs/datasets.md).

With ``--renderer warp`` (the default) the camera renders every world in one MuJoCo Warp
launch; ``--renderer opengl`` renders one world at a time. The JSON lists what differs from
the job's own config under ``changes``.

``--case camera``: PushCube-v1 with a 128x128 RGB Warp camera in its observation
(``sensor`` of the env), env-steps/s at each ``--num-envs`` with zero actions.

``--case syncs``: the host waits of the main job's scripted plan and of its steps, with their
call sites (``main_job_syncs.py``; torch's sync check on CUDA).

``--smoke`` runs every case with 2 envs on Warp's CPU device, the job's camera at 64x36 (a
correctness run of this script, not a measurement).

Usage:
    python benchmarks/gpu_main_job.py --device cuda --num-envs 64 256 1024
    python benchmarks/gpu_main_job.py --case camera --device cuda --num-envs 1024 4096
    python benchmarks/gpu_main_job.py --case syncs --device cuda --num-envs 1024
    python benchmarks/gpu_main_job.py --smoke
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from typing import Any, Callable, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_DATASETS_OFFLINE", "1")

from common import machine_info, print_table, write_json  # noqa: E402
from main_job_syncs import measure_syncs  # noqa: E402
from record_main_job import main_job_config  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "gpu_main_job.json")
PHASES = ("physics", "render", "demo_ik", "device_to_host")


class PhaseClock:
    """Seconds per phase of wrapped calls, each between two device syncs."""

    def __init__(self, device: str):
        import torch

        cuda = device.startswith("cuda")
        self.sync: Callable[[], None] = torch.cuda.synchronize if cuda else (lambda: None)
        self.seconds = dict.fromkeys(PHASES, 0.0)

    def wrap(self, owner: Any, name: str, phase: str) -> None:
        """Time ``owner.name`` calls under ``phase`` (an instance attribute shadows the method)."""
        original = getattr(owner, name)

        def timed(*args: Any, **kwargs: Any) -> Any:
            self.sync()
            started = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.sync()
                self.seconds[phase] += time.perf_counter() - started

        setattr(owner, name, timed)


def job_config(save_path: str, num_envs: int, episodes: int, args: argparse.Namespace) -> tuple[str, list[str]]:
    """The main job's config for this run, written into ``save_path``; its path and the changes made."""
    device, renderer = args.device, args.renderer
    with open(main_job_config(), encoding="utf-8") as f:
        cfg = json.load(f)
    cfg["env"]["dataset"]["lerobot"]["params"]["save_path"] = save_path
    cfg.update(num_envs=num_envs, max_episodes=episodes, backend="warp", device=device)
    changes = [f"backend warp on {device}", f"{num_envs} envs", f"camera renderer {renderer}"]
    if args.encoder_processes != "auto":
        cfg["env"]["dataset"]["lerobot"]["params"]["encoder_processes"] = int(args.encoder_processes)
        changes.append(f"{args.encoder_processes} encoder processes")
    for sensor in cfg["sensor"]:
        sensor["renderer"] = renderer
        if args.image_size:
            _resize(sensor, *args.image_size)
            changes.append("camera {}x{}".format(*args.image_size))
    path = os.path.join(save_path, "main_job.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(cfg, f)
    return path, changes


def _resize(sensor: dict, width: int, height: int) -> None:
    """A camera config at ``width`` x ``height`` with its intrinsics scaled along."""
    sx, sy = width / sensor["width"], height / sensor["height"]
    for key in ("intrinsics", "intrinsics_right"):
        if sensor.get(key):
            fx, fy, cx, cy = sensor[key]
            sensor[key] = [fx * sx, fy * sy, cx * sx, cy * sy]
    sensor["width"], sensor["height"] = width, height


def instrument(env: Any, clock: PhaseClock) -> None:
    """Wrap the phases' calls of a built main-job env."""
    base = env.unwrapped
    clock.wrap(base.sim, "advance", "physics")
    for sensor in base.sensors.values():
        clock.wrap(sensor, "update", "render")
    clock.wrap(base, "create_demo_action_list", "demo_ik")
    if base.dataset_manager is not None:
        clock.wrap(base.dataset_manager, "record_step", "device_to_host")


def recorded_frames(paths: list) -> tuple[int, int]:
    """``(episodes, frames)`` the finalized datasets hold, loaded back with lerobot."""
    from embodichain_lerobot.reading import load_dataset

    episodes = frames = 0
    for path in paths:
        dataset = load_dataset(path)
        episodes += int(dataset.meta.total_episodes)
        frames += int(dataset.num_frames)
    return episodes, frames


def measure_main_job(num_envs: int, args: argparse.Namespace, workdir: str) -> dict[str, Any]:
    """One row of ``--case main_job``."""
    import resource

    from embodichain_core.cli.run_env import build_parser, prepare
    from embodichain_core.cli.run_loops import RunStats, make_env, run_episodes

    save_path = tempfile.mkdtemp(prefix=f"main_job_{num_envs}_", dir=workdir)
    episodes = num_envs * args.episodes_per_env
    cfg_path, changes = job_config(save_path, num_envs, episodes, args)
    argv = ["--gym_config", cfg_path, "--headless", "--quiet", "--max_episodes", str(episodes), "--seed", "0"]
    plan = prepare(build_parser().parse_args(argv))
    started = time.perf_counter()
    env = make_env(plan)
    build_s = time.perf_counter() - started
    clock, stats = PhaseClock(args.device), RunStats()
    instrument(env, clock)
    writer_before = _children_cpu(resource)
    started = time.perf_counter()
    run_episodes(env, plan.extras, stats)
    run_s = time.perf_counter() - started
    started = time.perf_counter()
    env.close()
    flush_s = time.perf_counter() - started
    paths = [str(p) for p in env.unwrapped.dataset_manager.finalize() if p]
    saved, frames = recorded_frames(paths)
    return {
        "case": "main_job",
        "num_envs": num_envs,
        "build_s": build_s,
        "run_s": run_s,
        "flush_s": flush_s,
        "env_steps": stats.env_steps,  # summed over the envs
        "episodes_saved": saved,
        "frames_recorded": frames,
        "recorded_env_steps_per_s": frames / (run_s + flush_s),
        "phases_s": {**clock.seconds, "encoding_writing_cpu": _children_cpu(resource) - writer_before},
        "changes": changes,
    }


def _children_cpu(resource: Any) -> float:
    """CPU seconds of this process's finished children (the recorder's writer and encoder processes)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def camera_env(num_envs: int, device: str, size: int) -> Any:
    """PushCube-v1 on backend warp with a ``size`` x ``size`` RGB Warp camera in its observation."""
    import gymnasium as gym

    import embodichain_core  # noqa: F401  (loads the plugins)
    from embodichain_sensors.cfg import CameraCfg
    from embodichain_tasks.rl.push_cube import PushCubeCfg

    cfg = PushCubeCfg()
    cfg.sim_cfg.backend, cfg.sim_cfg.sim_device = "warp", device
    eye = CameraCfg.ExtrinsicsCfg(eye=(1.2, 0.0, 1.0), target=(0.4, 0.0, 0.1))
    cfg.sensor = [CameraCfg(uid="cam", width=size, height=size, renderer="warp", extrinsics=eye)]
    env = gym.make("PushCube-v1", cfg=cfg, num_envs=num_envs, seed=0, verbose=False).unwrapped
    env.reset(seed=0)
    return env


def measure_camera(num_envs: int, args: argparse.Namespace) -> dict[str, Any]:
    """One row of ``--case camera``: env-steps/s with the camera image in every observation."""
    import torch

    env = camera_env(num_envs, args.device, args.camera_size)
    sync = torch.cuda.synchronize if args.device.startswith("cuda") else (lambda: None)
    action = torch.zeros(env.action_space.shape, device=env.device)
    obs, *_ = env.step(action)  # the first render compiles or loads the kernel
    image = obs["sensor"]["cam"]["color"]
    sync()
    started = time.perf_counter()
    for _ in range(args.steps):
        env.step(action)
    sync()
    elapsed = time.perf_counter() - started
    env.close()
    return {
        "case": "camera",
        "num_envs": num_envs,
        "image_shape": list(image.shape),
        "steps": args.steps,
        "env_steps_per_s": args.steps * num_envs / elapsed,
    }


def _parse(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--case", choices=("main_job", "camera", "syncs"), nargs="+", default=["main_job"])
    p.add_argument("--device", default="cuda", help="cuda, cuda:N or cpu (Warp's CPU device)")
    p.add_argument("--num-envs", type=int, nargs="+", default=[64, 256, 1024])
    p.add_argument("--episodes-per-env", type=int, default=1)
    p.add_argument("--renderer", choices=("warp", "opengl"), default="warp")
    p.add_argument("--camera-size", type=int, default=128, help="--case camera: the image side")
    p.add_argument(
        "--image-size", type=int, nargs=2, metavar=("W", "H"), help="the job's camera size (its own: 320x180)"
    )
    p.add_argument("--steps", type=int, default=50, help="timed env steps per camera row, counted steps per syncs row")
    p.add_argument(
        "--encoder-processes",
        default="auto",
        type=lambda v: v if v == "auto" else int(v),
        help="the recorder's encoder_processes: an int, or auto (the job's default)",
    )
    p.add_argument("--out", default=DEFAULT_OUT)
    p.add_argument("--smoke", action="store_true", help="2 envs on Warp's CPU device, both cases, few steps")
    args = p.parse_args(argv)
    if args.smoke:  # a small job camera: Warp's CPU device traces rays on one thread
        args.case, args.device, args.num_envs, args.steps = ["main_job", "camera", "syncs"], "cpu", [2], 2
        args.image_size = args.image_size or [64, 36]
    return args


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = _parse(argv)
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="gpu_main_job_") as workdir:
        for n in args.num_envs:
            if "main_job" in args.case:
                rows.append(measure_main_job(n, args, workdir))
            if "camera" in args.case:
                rows.append(measure_camera(n, args))
            if "syncs" in args.case:
                rows.append(measure_syncs(n, args, workdir))
    payload = {"settings": vars(args), "machine": machine_info(), "rows": rows}
    write_json(args.out, payload)
    _print(rows)
    return payload


def _print(rows: list[dict[str, Any]]) -> None:
    job = [{**r, **{f"t_{k}": v for k, v in r["phases_s"].items()}} for r in rows if r["case"] == "main_job"]
    columns = [
        ("num_envs", "envs", "d"),
        ("episodes_saved", "saved", "d"),
        ("recorded_env_steps_per_s", "recorded/s", ".1f"),
    ]
    phases = [(f"t_{p}", p, ".1f") for p in (*PHASES, "encoding_writing_cpu")] + [("flush_s", "flush", ".1f")]
    if job:
        print_table(job, columns + phases, title="Data-generation job on backend warp (seconds per phase)")
    camera = [r for r in rows if r["case"] == "camera"]
    if camera:
        print_table(
            camera,
            [("num_envs", "envs", "d"), ("env_steps_per_s", "env-steps/s", ".0f")],
            title="PushCube-v1 with a Warp camera",
        )
    syncs = [r for r in rows if r["case"] == "syncs"]
    if syncs:
        print_table(
            syncs,
            [("num_envs", "envs", "d"), ("per_step", "waits/step", ".2f"), ("plan_syncs", "waits/plan", ".0f")],
            title="Host waits of the main job (torch's sync check on CUDA, Warp's waits)",
        )


if __name__ == "__main__":
    main()
