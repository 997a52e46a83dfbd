"""Camera sensor rendering throughput against a bare ``mujoco.Renderer``.

For 128x128 and 640x480, RGB and RGB+depth+mask, it measures rendered frames per
second of an embodichain-sensors ``Camera`` (``sensor.update()``: N envs = N
frames) and of a bare ``mujoco.Renderer`` rendering the same model from the same
camera in the same run, with the same fast settings (no shadows, reflections or
MSAA), and reports the ratio (target >= 0.8). The bare renderer needs three
renders for RGB+depth+mask; the sensor reads colour and depth from one render
and the mask from a second. MuJoCo's default settings (shadows, reflections,
4x MSAA) are measured too, for reference.

Timing follows benchmarks/common.py: warm-up, interleaved rounds, medians.

A second table (benchmarks/render_warp.py) puts cameras on backend ``warp``: MuJoCo Warp's
batched renderer beside the per-world OpenGL renderer, frames/s and env-steps/s at
``--warp-worlds`` worlds, 128x128 and 320x180.

Usage:
    .venv/bin/python benchmarks/render_throughput.py [--rounds 7] [--frames 20] [--num-envs 1]
    .venv/bin/python benchmarks/render_throughput.py --device cuda --warp-worlds 1024,4096  # GPU
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Callable

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import embodichain_core.sim  # noqa: E402,F401  (chooses MUJOCO_GL before mujoco is imported)
import mujoco  # noqa: E402

from render_warp import WARP_COLUMNS, add_arguments, warp_rows  # noqa: E402
from common import (
    interleaved_timings,
    machine_info,
    median,
    print_table,
    camera_scene,
    spread,
    write_json,
)

RESULTS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "render_throughput.json")
SIZES = ((128, 128), (640, 480))
MODES: dict[str, dict[str, Any]] = {"rgb": {}, "rgb+depth+mask": {"enable_depth": True, "enable_mask": True}}


def build(width: int, height: int, num_envs: int, mode: str) -> tuple[Any, Any]:
    """The benchmark scene with one camera of ``mode``; returns (scene, camera)."""
    return camera_scene(width, height, num_envs, **MODES[mode])


def bare_renderer(scene: Any, width: int, height: int, fast: bool) -> mujoco.Renderer:
    """A ``mujoco.Renderer`` of the scene model (fast: created without MSAA)."""
    vis = scene.model.vis.quality
    samples = vis.offsamples
    if fast:
        vis.offsamples = 0
    try:
        return mujoco.Renderer(scene.model, height=height, width=width)
    finally:
        vis.offsamples = samples


def bare_frames(
    scene: Any, renderer: mujoco.Renderer, camera: str, mode: str, fast: bool, frames: int
) -> Callable[[], None]:
    """``frames`` renders per env of the bare renderer (3 per frame for rgb+depth+mask)."""
    datas = [mujoco.MjData(scene.model) for _ in range(scene.num_envs)]
    flags = mujoco.mjtRndFlag

    def run() -> None:
        for _ in range(frames):
            for i, data in enumerate(datas):
                scene.sim.get_data(i, data)
                renderer.update_scene(data, camera)
                if fast:
                    renderer.scene.flags[flags.mjRND_SHADOW] = renderer.scene.flags[flags.mjRND_REFLECTION] = 0
                renderer.render()
                if mode != "rgb":
                    renderer.enable_depth_rendering()
                    renderer.render()
                    renderer.enable_segmentation_rendering()
                    renderer.render()
                    renderer.disable_segmentation_rendering()

    return run


def measure(width: int, height: int, mode: str, args: argparse.Namespace) -> dict[str, Any]:
    """One row: sensor and bare fps (and MuJoCo-default fps for RGB), interleaved."""
    scene, camera = build(width, height, args.num_envs, mode)
    fast = bare_renderer(scene, width, height, fast=True)
    contenders = {
        "sensor": lambda: [camera.update() for _ in range(args.frames)],
        "bare": bare_frames(scene, fast, "cam", mode, True, args.frames),
    }
    default = None
    if mode == "rgb" and not args.skip_default:
        default = bare_renderer(scene, width, height, fast=False)
        contenders["default"] = bare_frames(scene, default, "cam", mode, False, max(1, args.frames // 10))
    times = interleaved_timings(contenders, repeats=args.rounds, warmup=1)
    n = args.num_envs
    fps = {"sensor": n * args.frames / median(times["sensor"]), "bare": n * args.frames / median(times["bare"])}
    row = {
        "resolution": f"{width}x{height}",
        "mode": mode,
        "num_envs": n,
        "sensor_fps": fps["sensor"],
        "bare_fps": fps["bare"],
        "ratio": fps["sensor"] / fps["bare"],
        "spread_sensor": spread(times["sensor"]),
        "spread_bare": spread(times["bare"]),
        "default_settings_fps": (n * max(1, args.frames // 10) / median(times["default"])) if default else None,
    }
    for r in (fast, default):
        if r is not None:
            r.close()
    camera.close()
    return row


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7, help="interleaved rounds per contender")
    parser.add_argument("--frames", type=int, default=20, help="frames (updates) per round")
    parser.add_argument("--num-envs", type=int, default=1)
    parser.add_argument("--skip-default", action="store_true", help="skip MuJoCo's default (slow) settings")
    parser.add_argument("--out", default=RESULTS)
    parser.add_argument("--skip-opengl-table", action="store_true", help="only the backend-warp table")
    add_arguments(parser)
    args = parser.parse_args(argv)
    rows = [] if args.skip_opengl_table else [measure(w, h, mode, args) for (w, h) in SIZES for mode in MODES]
    columns = [
        ("resolution", "resolution", "s"),
        ("mode", "outputs", "s"),
        ("sensor_fps", "sensor fps", ".0f"),
        ("bare_fps", "bare mujoco.Renderer fps", ".0f"),
        ("ratio", "ratio", ".2f"),
        ("default_settings_fps", "MuJoCo defaults fps", ".1f"),
    ]
    if rows:
        print_table(
            rows, columns, title=f"Camera rendering, {args.num_envs} env(s), MUJOCO_GL={os.environ.get('MUJOCO_GL')}"
        )
    warp = warp_rows(args)
    if warp:
        print_table(warp, WARP_COLUMNS, title=f"Cameras on backend warp (RGB, device {args.device})")
    payload = {
        "benchmark": "render_throughput",
        "target_ratio": 0.8,
        "backend": os.environ.get("MUJOCO_GL"),
        "settings": vars(args),
        "machine": machine_info(),
        "rows": rows,
        "warp_rows": warp,
    }
    write_json(args.out, payload)
    print(f"wrote {args.out}")
    return payload


if __name__ == "__main__":
    main()
