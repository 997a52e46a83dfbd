"""Shared helpers of the benchmarks: scene generator, timing, JSON, tables.

Timing follows the project's rule for this shared 2-core box: warm up first,
repeat each measurement several times, interleave the things being compared
(so a noisy neighbour hits both alike) and report medians.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence


def seven_dof_arm_mjcf() -> str:
    """The 7-DoF arm with a two-finger gripper (mimic second finger) of the core's demo."""
    from embodichain_core.demo.arm import arm7_mjcf

    return arm7_mjcf()


# -- timing --------------------------------------------------------------------------------------
#: ``wall``: elapsed time; ``cpu``: CPU time of this process, all its threads summed (what a busy
#: neighbour does not inflate; equal to the wall time of an idle box for one-threaded work).
CLOCKS: dict[str, Callable[[], float]] = {"wall": time.perf_counter, "cpu": time.process_time}


def camera_scene(width: int, height: int, num_envs: int, sim_cfg: Any = None, **camera: Any) -> tuple[Any, Any]:
    """The render benchmarks' scene (7-DoF arm, table, cube, point light) with one camera.

    Args:
        width: image width in pixels.
        height: image height in pixels.
        num_envs: envs (worlds) of the scene.
        sim_cfg: the ``SimulationManagerCfg`` (default: the CPU ``mujoco_batch`` one).
        **camera: further ``CameraCfg`` fields (``enable_depth``, ``renderer``, ...).

    Returns:
        ``(scene, camera)``, the scene built.
    """
    from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg, SimulationManagerCfg
    from embodichain_core.sim.scene import Scene
    from embodichain_core.sim.shapes import CubeCfg
    from embodichain_sensors.camera import Camera
    from embodichain_sensors.cfg import CameraCfg

    scene = Scene(sim_cfg if sim_cfg is not None else SimulationManagerCfg(), num_envs=num_envs)
    scene.add_robot(RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf()))
    scene.add_light(LightCfg(uid="lamp", init_pos=(0.5, 0.5, 2.0)))
    table = RigidObjectCfg(
        uid="table", shape=CubeCfg(size=[0.6, 0.8, 0.4]), init_pos=(0.6, 0.0, 0.2), body_type="kinematic"
    )
    scene.add_rigid_object(table, background=True)
    scene.add_rigid_object(RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05] * 3), init_pos=(0.5, 0.1, 0.43)))
    f = 0.9 * width
    cfg = CameraCfg(
        uid="cam",
        width=width,
        height=height,
        intrinsics=(f, f, width / 2 - 0.5, height / 2 - 0.5),
        extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1.6, -0.9, 1.3), target=(0.4, 0.0, 0.4)),
        **camera,
    )
    cam = Camera(cfg, scene)
    scene.add_sensor(cam)
    scene.build()
    return scene, cam


def time_once(fn: Callable[[], Any], clock: str = "wall") -> float:
    """Seconds of one call of ``fn`` on ``clock`` (see :data:`CLOCKS`)."""
    now = CLOCKS[clock]
    start = now()
    fn()
    return now() - start


def interleaved_timings(
    fns: Mapping[str, Callable[[], Any]], repeats: int, warmup: int = 1, clock: str = "wall"
) -> dict[str, list[float]]:
    """Call every function ``warmup`` times, then ``repeats`` rounds of all of them in turn.

    Returns ``{name: [seconds per round]}`` on ``clock`` (see :data:`CLOCKS`). Interleaving
    makes background load (other processes on a shared box) hit every contender alike.
    """
    for _ in range(max(0, warmup)):
        for fn in fns.values():
            fn()
    out: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(max(1, repeats)):
        for name, fn in fns.items():
            out[name].append(time_once(fn, clock))
    return out


def cycling(step: Callable[[Any], Any], actions: Sequence[Any]) -> Callable[[int], None]:
    """``run(n)``: ``n`` calls of ``step``, cycling through ``actions`` and going on where the
    previous ``run`` stopped (every contender of a benchmark sees the same sequence)."""
    state = {"k": 0}

    def run(n: int) -> None:
        k = state["k"]
        for i in range(k, k + n):
            step(actions[i % len(actions)])
        state["k"] = k + n

    return run


def median(values: Sequence[float]) -> float:
    return float(statistics.median(values))


def spread(values: Sequence[float]) -> float:
    """Relative spread (max - min) / median of ``values``; 0 for one value."""
    if len(values) < 2:
        return 0.0
    mid = statistics.median(values)
    return float((max(values) - min(values)) / mid) if mid else 0.0


# -- machine and output ------------------------------------------------------------------------------
def machine_info() -> dict[str, Any]:
    """What the numbers were measured on (versions and core count)."""
    info: dict[str, Any] = {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpu_count": os.cpu_count(),
    }
    try:
        info["cpu_affinity"] = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        pass
    for module in ("mujoco", "torch", "numpy"):
        try:
            info[module] = __import__(module).__version__
        except Exception:  # pragma: no cover - reporting only
            info[module] = None
    try:
        import torch

        info["torch_threads"] = torch.get_num_threads()
    except Exception:  # pragma: no cover
        pass
    return info


def write_json(path: str, payload: Any) -> str:
    """Write ``payload`` as indented JSON (creating folders); return the path."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(payload, fh, indent=2, sort_keys=False)
        fh.write("\n")
    return path


def format_table(rows: Iterable[Mapping[str, Any]], columns: Sequence[tuple[str, str, str]]) -> str:
    """A Markdown table. ``columns`` are ``(key, header, format spec)`` triples."""
    rows = list(rows)
    header = [h for _, h, _ in columns]
    body = [[format(row[key], spec) if row.get(key) is not None else "-" for key, _, spec in columns] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in body)) if body else len(h) for i, h in enumerate(header)]
    lines = [
        "| " + " | ".join(h.rjust(w) for h, w in zip(header, widths)) + " |",
        "|" + "|".join("-" * (w + 1) + ":" for w in widths) + "|",
    ]
    lines += ["| " + " | ".join(c.rjust(w) for c, w in zip(r, widths)) + " |" for r in body]
    return "\n".join(lines)


def print_table(
    rows: Iterable[Mapping[str, Any]],
    columns: Sequence[tuple[str, str, str]],
    title: Optional[str] = None,
    file: Any = None,
) -> None:
    file = file or sys.stdout
    if title:
        print(title, file=file)
    print(format_table(rows, columns), file=file)
    file.flush()
