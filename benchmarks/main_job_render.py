"""The main job's recorded env-steps/s against its render-bound limit.

The main job (``make run``: PickFork-v1, 2 envs, a 320x180 stereo camera, scripted demos
recorded by ``AsyncLeRobotRecorder`` with H.264 videos) runs for ``--rounds`` rounds of
``--episodes`` saved episodes in one process. While it runs, every env state its camera
renders is captured (``mj_getState`` of the full physics state, and the env's per-env model
fields). After each round a bare ``mujoco.Renderer`` (fast settings: no MSAA, shadows or
reflections, as the sensor) renders the same cameras (the model's ``eye_in_head/left`` and
``/right``) at the same resolution and modalities from the same states: the time of its
``update_scene`` + ``render`` calls alone is the render-bound limit. Reported per round and
as medians:

* ``env_steps_per_s``: recorded env steps over the episode loop's time (what ``run-env``
  prints), the capture's own time taken out;
* ``limit_steps_per_s``: the same env steps over the bare loop's render time;
* ``ratio``: the first over the second (the target is >= 0.8).

A last, profiled round (cProfile, with a ``mjr_finish`` after each ``mjr_render`` so that
rasterization and read-back separate) breaks the main job's time down: scene update,
rasterization, read-back, conversion to the output tensors, segmentation and depth passes,
the rest of the camera's Python, physics, the scripted planner, the recorder, the rest.

Usage:
    .venv/bin/python benchmarks/main_job_render.py                 # 3 rounds of 2 episodes
    .venv/bin/python benchmarks/main_job_render.py --rounds 1 --out ''   # quick look
    .venv/bin/python benchmarks/main_job_render.py --depth-masks   # with depth and masks
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import sys
import tempfile
import time
from typing import Any, Optional

from embodichain_core.rendering import configure_gl

configure_gl()  # MUJOCO_GL before mujoco is imported, for the bare mujoco.Renderer too

import mujoco  # noqa: E402
import mujoco.batch  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import machine_info, median, spread, write_json  # noqa: E402
from record_main_job import main_job_config  # noqa: E402

_FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


class CapturingReader:
    """Wraps a camera's per-env reader: every ``data(i)`` it hands out is captured as
    ``(env, state, per-env model fields)``; its own time is summed in ``seconds``."""

    def __init__(self, reader: Any, sim: Any):
        self.reader, self.sim, self.seconds = reader, sim, 0.0
        self.frames: list[tuple[int, np.ndarray, dict[str, np.ndarray]]] = []
        self.fields: Optional[list[str]] = None

    def model(self, env_id: int) -> mujoco.MjModel:
        return self.reader.model(env_id)

    def data(self, env_id: int) -> mujoco.MjData:
        data = self.reader.data(env_id)
        started = time.perf_counter()
        model, batch = self.sim.model, self.sim.batch
        if self.fields is None:  # the per-env fields (the reset events expanded them at startup)
            self.fields = sorted(n for n in mujoco.batch.MODEL_FIELDS if batch.expanded(n) is not None)
        state = np.empty(mujoco.mj_stateSize(model, _FULL))
        mujoco.mj_getState(model, data, state, _FULL)
        rows = {n: np.array(batch.expanded(n)[env_id]) for n in self.fields}
        self.frames.append((int(env_id), state, rows))
        self.seconds += time.perf_counter() - started
        return data


def build_env(save_path: str, depth_masks: bool, seed: int) -> tuple[Any, Any]:
    """The main job's env (recorded into ``save_path``) and its run plan."""
    from embodichain_core.cli.run_env import build_parser, prepare
    from embodichain_core.cli.run_loops import make_env

    with open(main_job_config(), encoding="utf-8") as f:
        cfg = json.load(f)
    cfg["env"]["dataset"]["lerobot"]["params"]["save_path"] = save_path
    for sensor in cfg["sensor"] if depth_masks else ():
        sensor.update(enable_depth=True, enable_mask=True)
    path = os.path.join(save_path, "main_job.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(cfg, f)
    argv = ["--gym_config", path, "--headless", "--quiet", "--seed", str(seed)]
    plan = prepare(build_parser().parse_args(argv))
    return make_env(plan), plan


def run_round(env: Any, plan: Any, episodes: int) -> dict[str, Any]:
    """``episodes`` more saved episodes; the loop's time and env steps."""
    from embodichain_core.cli.run_loops import RunStats, run_episodes

    manager = env.unwrapped.dataset_manager
    extras = dict(plan.extras, max_episodes=int(manager.committed_episodes) + episodes)
    stats = RunStats()
    cpu = time.process_time()
    run_episodes(env, extras, stats)
    return {"run_s": stats.run_s, "cpu_s": time.process_time() - cpu, "env_steps": stats.env_steps}


class BareLoop:
    """A ``mujoco.Renderer`` of the scene model with the sensor's fast settings, rendering
    the sensor's model cameras from captured states."""

    def __init__(self, sim: Any, camera: Any):
        cfg = camera.cfg
        self.model = sim.batch.get_model(0)  # a model of its own, with per-env fields to write
        quality = self.model.vis.quality
        samples, quality.offsamples = quality.offsamples, 0
        try:
            self.renderer = mujoco.Renderer(self.model, height=cfg.height, width=cfg.width)
        finally:
            quality.offsamples = samples
        self.data = mujoco.MjData(self.model)
        self.cameras = [v.camera_id for v in camera.views]
        self.depth, self.mask = bool(cfg.enable_depth), bool(cfg.enable_mask)

    def replay(self, frames: list) -> float:
        """Seconds of ``update_scene`` + ``render`` for every captured frame and camera
        (writing the states in is not timed); their CPU seconds (all threads) in ``cpu_s``."""
        model, data, r = self.model, self.data, self.renderer
        flags, total, cpu = mujoco.mjtRndFlag, 0.0, 0.0
        for _, state, rows in frames:
            for name, row in rows.items():  # bvh_aabb: the bodies' volumes lead the field
                getattr(model, name)[: len(row)] = row
            mujoco.mj_setState(model, data, state, _FULL)
            mujoco.mj_forward(model, data)
            started, cpu_started = time.perf_counter(), time.process_time()
            for cam in self.cameras:
                r.update_scene(data, cam)
                r.scene.flags[flags.mjRND_SHADOW] = r.scene.flags[flags.mjRND_REFLECTION] = 0
                r.render()
                if self.depth:
                    r.enable_depth_rendering()
                    r.render()
                    r.disable_depth_rendering()
                if self.mask:
                    r.enable_segmentation_rendering()
                    r.render()
                    r.disable_segmentation_rendering()
            total += time.perf_counter() - started
            cpu += time.process_time() - cpu_started
        self.cpu_s = cpu
        return total


class _FinishAfterRender:
    """``mujoco`` for the sensor renderer's module during the profiled round: ``mjr_render``
    is followed by ``mjr_finish``, so rasterization is timed apart from the read-back."""

    def __getattr__(self, name: str) -> Any:
        return getattr(mujoco, name)

    @staticmethod
    def mjr_render(*args: Any) -> None:
        mujoco.mjr_render(*args)
        mujoco.mjr_finish()


def profile_round(env: Any, plan: Any, episodes: int, clock: str) -> dict[str, float]:
    """One more round under cProfile on ``clock`` (``cpu``: this process's CPU time, every
    thread, steadier on a busy machine; ``wall``); the breakdown in ms per env step."""
    from embodichain_sensors import renderer as renderer_module

    profiler = cProfile.Profile(time.process_time if clock == "cpu" else time.perf_counter)
    renderer_module.mujoco = _FinishAfterRender()  # type: ignore[assignment]
    try:
        profiler.enable()
        result = run_round(env, plan, episodes)
        profiler.disable()
    finally:
        renderer_module.mujoco = mujoco
    total = result["cpu_s"] if clock == "cpu" else result["run_s"]
    return breakdown(pstats.Stats(profiler), total, result["env_steps"])


def _time(stats: pstats.Stats, func: str, file_part: str = "", cumulative: bool = True) -> float:
    """Seconds in ``func`` (of a file whose path contains ``file_part``; builtins: ``~``)."""
    total = 0.0
    for (path, _, name), (_, _, tt, ct, _) in stats.stats.items():  # type: ignore[attr-defined]
        if name == func and file_part in path:
            total += ct if cumulative else tt
    return total


def breakdown(stats: pstats.Stats, total_s: float, env_steps: int) -> dict[str, float]:
    """Where the profiled round's ``total_s`` went, ms per env step."""
    builtin = "<built-in method mujoco.{}>"
    parts = {
        "scene_update": _time(stats, "update_scene", "embodichain_sensors"),
        "rasterization": _time(stats, builtin.format("_render.mjr_render"))
        + _time(stats, builtin.format("_render.mjr_finish")),
        "read_back": _time(stats, builtin.format("_render.mjr_readPixels")),
        "segmentation_pass": _time(stats, "render_segmentation", "embodichain_sensors"),
    }
    render = _time(stats, "render", "embodichain_sensors/renderer.py")
    # the rest of SensorRenderer.render: the depth linearization when depth is on, the call itself
    parts["render_call_rest"] = max(0.0, render - parts["rasterization"] - parts["read_back"])
    view = _time(stats, "_render_view", "embodichain_sensors/camera.py")
    parts["conversion"] = (
        max(0.0, view - render - parts["segmentation_pass"])
        + _time(stats, "_alloc", "embodichain_sensors/camera.py")
        + _time(stats, "_outputs", "embodichain_sensors/stereo.py")
    )
    camera = _time(stats, "update", "embodichain_sensors/camera.py")
    parts["camera_python"] = max(0.0, camera - sum(parts.values()))
    parts["physics"] = _time(stats, builtin.format("_batch.step")) + _time(stats, builtin.format("_batch.forward"))
    parts["scripted_planner"] = _time(stats, "create_demo_action_list")
    parts["recorder"] = _time(stats, "record_step", "dataset_manager") + _time(stats, "record_reset", "dataset_manager")
    parts["rest"] = max(0.0, total_s - camera - sum(parts[k] for k in ("physics", "scripted_planner", "recorder")))
    steps = max(1, env_steps)
    out = {k: 1e3 * v / steps for k, v in parts.items()}
    out["camera_total"] = 1e3 * camera / steps
    out["total"] = 1e3 * total_s / steps
    return out


def timed_round(env: Any, plan: Any, capture: CapturingReader, bare: BareLoop, episodes: int) -> dict[str, Any]:
    """One round of the main job, then the bare loop on the states it rendered."""
    capture.frames, capture.seconds = [], 0.0
    main = run_round(env, plan, episodes)
    run_s = main["run_s"] - capture.seconds
    bare_s = bare.replay(capture.frames)
    return {
        **main,
        "capture_s": capture.seconds,
        "frames": len(capture.frames) * len(bare.cameras),
        "bare_render_s": bare_s,
        "bare_render_cpu_s": bare.cpu_s,
        "env_steps_per_s": main["env_steps"] / run_s,
        "limit_steps_per_s": main["env_steps"] / bare_s,
        "ratio": bare_s / run_s,
        "cpu_ratio": bare.cpu_s / (main["cpu_s"] - capture.seconds),
    }


def measure(args: argparse.Namespace, workdir: str) -> dict[str, Any]:
    """Rounds of every ``render_threads`` contender in turn (each round: the main job, then
    the bare loop on its states), then the profiled round (one render thread)."""
    env, plan = build_env(workdir, args.depth_masks, args.seed)
    base = env.unwrapped
    camera = base.sensors["eye_in_head"]
    capture = CapturingReader(camera._envs, base.scene.sim)
    camera._envs = capture
    bare = BareLoop(base.scene.sim, camera)
    rounds: dict[str, list] = {str(t): [] for t in args.render_threads}
    try:
        for _ in range(max(1, args.rounds)):
            for threads in args.render_threads:
                camera.cfg.render_threads = threads
                rounds[str(threads)].append(timed_round(env, plan, capture, bare, args.episodes))
                shown = ", ".join(f"{k} {v:.3g}" for k, v in rounds[str(threads)][-1].items())
                print(f"render_threads {threads}: {shown}", flush=True)
        camera._envs, camera.cfg.render_threads = capture.reader, 1
        profile = profile_round(env, plan, args.episodes, args.clock) if args.profile else None
    finally:
        env.close()
        base.dataset_manager.finalize()
    return {"rounds": rounds, "breakdown_ms_per_env_step": profile}


def summarize(rounds: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians over one contender's timed rounds."""
    keys = ("env_steps_per_s", "limit_steps_per_s", "ratio", "cpu_ratio")
    out: dict[str, Any] = {k: median([r[k] for r in rounds]) for k in keys}
    out["ratio_spread"] = spread([r["ratio"] for r in rounds])
    out["meets_target"] = out["ratio"] >= 0.8
    return out


def _parse(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rounds", type=int, default=3, help="timed rounds (default 3)")
    p.add_argument("--episodes", type=int, default=2, help="saved episodes per round (default 2: one per env)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--depth-masks", action="store_true", help="the camera also renders depth and masks")
    p.add_argument(
        "--render-threads",
        type=int,
        nargs="+",
        default=[1, 2],
        help="the camera's render_threads, one contender each, interleaved (default: 1 2)",
    )
    p.add_argument("--clock", choices=("cpu", "wall"), default="cpu", help="the profiled round's clock (default cpu)")
    p.add_argument("--no-profile", dest="profile", action="store_false", help="skip the profiled round")
    p.add_argument("--out", default="benchmarks/results/main_job_render.json", help="JSON output ('' writes none)")
    return p.parse_args(argv)


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = _parse(argv)
    info = machine_info()
    info["loadavg_before"] = os.getloadavg()
    info["mujoco_gl"] = os.environ.get("MUJOCO_GL")
    info["lp_num_threads"] = os.environ.get("LP_NUM_THREADS")
    with tempfile.TemporaryDirectory(prefix="main_job_render_") as workdir:
        result = measure(args, workdir)
    info["loadavg_after"] = os.getloadavg()
    summary = {threads: summarize(rs) for threads, rs in result["rounds"].items()}
    first = next(iter(result["rounds"].values()))
    for threads, rs in result["rounds"].items():  # paired: rounds next to each other share the load
        paired = [r["env_steps_per_s"] / f["env_steps_per_s"] for r, f in zip(rs, first)]
        summary[threads]["speedup_over_first"] = median(paired)
    payload = {"settings": vars(args), "summary": summary, **result, "machine": info}
    print()
    for threads, row in summary.items():
        print(
            f"render_threads {threads}: main job recorded {row['env_steps_per_s']:.1f} env-steps/s; bare "
            f"mujoco.Renderer limit {row['limit_steps_per_s']:.1f} env-steps/s; ratio {row['ratio']:.2f} "
            f"(spread {row['ratio_spread']:.2f}; target >= 0.8: {'met' if row['meets_target'] else 'not met'}); "
            f"CPU-time ratio {row['cpu_ratio']:.2f}; env-steps/s x{row['speedup_over_first']:.2f} of the first "
            "contender's (paired rounds)"
        )
    if result["breakdown_ms_per_env_step"]:
        print(f"\nprofiled round (render_threads 1), {args.clock} ms per env step:")
        for key, value in result["breakdown_ms_per_env_step"].items():
            print(f"  {key:20s} {value:7.2f}")
    if args.out:
        print("\nwrote", write_json(args.out, payload))
    return payload


if __name__ == "__main__":
    main()
