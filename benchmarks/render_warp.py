"""Cameras on backend ``warp``: MuJoCo Warp's batched renderer beside the per-world OpenGL one.

Part of ``render_throughput.py`` (same run, second table). For each world count and image
size, on one scene (7-DoF arm, table, cube, lamp) with one RGB camera, it measures:

* ``frames/s``: ``camera.update()`` alone (N worlds = N frames);
* ``env-steps/s``: one physics step of every world plus ``camera.update()``, times N.

``renderer: warp`` traces every world in one launch on ``--device`` (``cpu`` is Warp's CPU
device; ``cuda`` for 1024/4096 worlds on a GPU); ``renderer: opengl`` renders one world at
a time on the host (skipped above ``--opengl-max-worlds``). The first Warp update compiles
the render kernel (cached in ``.warp_cache``); it is a warm-up, not timed.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

WARP_SIZES = "128x128,320x180"


def build_warp(width: int, height: int, num_envs: int, renderer: str, device: str) -> tuple[Any, Any]:
    """The benchmark scene on backend warp with one RGB camera of ``renderer``."""
    from embodichain_core.sim.cfg import SimulationManagerCfg

    from common import camera_scene

    return camera_scene(
        width, height, num_envs, SimulationManagerCfg(backend="warp", sim_device=device), renderer=renderer
    )


def _rate(fn: Any, n: int, min_seconds: float) -> float:
    """Calls of ``fn`` per second (at least 2 calls and ``min_seconds``), times ``n``."""
    calls, start = 0, time.perf_counter()
    while calls < 2 or time.perf_counter() - start < min_seconds:
        fn()
        calls += 1
    return n * calls / (time.perf_counter() - start)


def measure_warp(width: int, height: int, worlds: int, renderer: str, args: argparse.Namespace) -> dict[str, Any]:
    """One row: frames/s and env-steps/s of ``renderer`` at ``worlds`` worlds."""
    scene, camera = build_warp(width, height, worlds, renderer, args.device)
    start = time.perf_counter()
    camera.update()  # compiles (or loads) the render kernel
    first = time.perf_counter() - start
    scene.sim.step(1)  # untimed: the first step compiles (or loads) MuJoCo Warp's physics kernels

    def step() -> None:
        scene.sim.step(1)
        camera.update()

    fps = _rate(camera.update, worlds, args.min_seconds)
    steps = _rate(step, worlds, args.min_seconds)
    camera.close()
    return {
        "renderer": renderer,
        "device": args.device,
        "worlds": worlds,
        "resolution": f"{width}x{height}",
        "frames_per_s": fps,
        "env_steps_per_s": steps,
        "first_update_s": first,
    }


def warp_rows(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Every (size, worlds, renderer) row the arguments ask for."""
    rows = []
    for width, height in (tuple(int(v) for v in size.split("x")) for size in args.warp_sizes.split(",") if size):
        for worlds in (int(w) for w in args.warp_worlds.split(",") if w):
            for renderer in ("warp", "opengl"):
                if renderer == "opengl" and worlds > args.opengl_max_worlds:
                    continue
                rows.append(measure_warp(width, height, worlds, renderer, args))
    return rows


WARP_COLUMNS = [
    ("resolution", "resolution", "s"),
    ("worlds", "worlds", "d"),
    ("renderer", "renderer", "s"),
    ("frames_per_s", "frames/s", ".0f"),
    ("env_steps_per_s", "env-steps/s", ".0f"),
    ("first_update_s", "first update s", ".1f"),
]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``--warp-*`` options of render_throughput.py."""
    parser.add_argument(
        "--warp-worlds", default="1,16,64", help="world counts on backend warp ('' skips; GPU: 1024,4096)"
    )
    parser.add_argument("--warp-sizes", default=WARP_SIZES, help="image sizes WxH of the warp rows")
    parser.add_argument("--device", default="cpu", help="sim_cfg.sim_device of the warp rows: cpu or cuda")
    parser.add_argument("--opengl-max-worlds", type=int, default=64, help="skip OpenGL rows above this")
    parser.add_argument("--min-seconds", type=float, default=2.0, help="time per warp-row measurement")
