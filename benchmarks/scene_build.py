"""Scene build time of the seed tutorial's scene, cold (empty coacd cache) and warm (second build).

The scene is the seed tutorial's (``modular_env``) without the robot and the camera: the
kinematic ``CircleTableSimple`` (``init_rot=(0, 90, 0)``, ``compute_uv``), the standard fork
(``body_scale=(0.75, 0.75, 1)``), the ``SlidingBoxDrawer`` URDF and a point light, from the
``embodichain-assets`` pack. Variants:

* ``seed``: exactly that;
* ``seed+fork_variants``: the fork with every file of ``TableWare/tableware/fork/`` reserved as
  a per-env mesh variant (what ``replace_assets_from_group`` needs), 4 envs;
* ``seed+mug_coacd``: plus the mug with ``max_convex_hull_num=8``, whose non-convex handle goes
  through coacd: the one variant where cold and warm differ by the decomposition;
* ``seed+w1``: plus the DexforceW1 robot, when ``embodichain_robots`` provides it.

"Cold" is the first build in a fresh Python process with ``EMBODICHAIN_CACHE_DIR`` pointing at a
new empty folder (the imports are timed separately); "warm" is the median of later builds in the
same process (modules imported, coacd results on disk). Each cold run is a new process.

Usage:
    python benchmarks/scene_build.py [--repeats 3] [--warm 5] [--out benchmarks/results/scene_build.json]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from typing import Any, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import machine_info, median, print_table, write_json  # noqa: E402

DEFAULT_OUT = os.path.join("benchmarks", "results", "scene_build.json")
TARGET_WARM_S = 2.0
VARIANTS = ("seed", "seed+fork_variants", "seed+mug_coacd", "seed+w1")
COLUMNS = [
    ("variant", "variant", ""),
    ("num_envs", "envs", "d"),
    ("import_s", "import [s]", ".3f"),
    ("cold_s", "cold build [s]", ".3f"),
    ("warm_s", "warm build [s]", ".3f"),
    ("coacd_calls_cold", "coacd runs cold", "d"),
    ("coacd_calls_warm", "coacd runs warm", "d"),
]


# -- worker (runs in a fresh process) -------------------------------------------------------------
def _robot_cfg() -> Any:
    """The W1 config through the robot registry (raises when the robots plugin lacks it)."""
    import embodichain_robots  # noqa: F401  (ImportError: plugin not installed)
    from embodichain_core.plugins import get_robot_cfg_class

    cls = get_robot_cfg_class("DexforceW1")
    return cls.from_dict(
        {"uid": "dexforce_w1", "version": "v021", "arm_kind": "anthropomorphic", "init_pos": [0.0, 0.0, 0.0]}
    )


def _builder(variant: str) -> tuple[Any, int]:
    """A zero-argument function building the variant's scene, and its number of envs."""
    from embodichain_assets.seed_scene import build_seed_scene, fork_variant_files

    if variant == "seed":
        return (lambda: build_seed_scene(1)), 1
    if variant == "seed+fork_variants":
        files = fork_variant_files()
        return (lambda: build_seed_scene(4, fork_variants=files)), 4
    if variant == "seed+w1":
        robot = _robot_cfg()
        return (lambda: build_seed_scene(1, robot_cfg=robot)), 1
    if variant == "seed+mug_coacd":
        return _mug_builder(), 1
    raise ValueError(f"unknown variant {variant!r}; variants: {VARIANTS}")


def _mug_builder() -> Any:
    """The seed scene plus a mug whose handle is decomposed (max_convex_hull_num=8)."""
    from embodichain_core.sim.cfg import RigidObjectCfg
    from embodichain_core.sim.shapes import MeshCfg

    mug = RigidObjectCfg(
        uid="mug", shape=MeshCfg(fpath="CoffeeCup/cup.ply", max_convex_hull_num=8), init_pos=(0.9, 0.2, 0.9)
    )
    return lambda: _seed_with_extra(mug)


def _seed_with_extra(extra: Any) -> Any:
    """The seed scene with one more rigid object."""
    from embodichain_assets.seed_scene import seed_scene_cfgs
    from embodichain_core.sim.cfg import SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    cfgs = seed_scene_cfgs()
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_rigid_object(cfgs["table"], background=True)
    scene.add_rigid_object(cfgs["fork"])
    scene.add_rigid_object(extra)
    scene.add_articulation(cfgs["drawer"])
    scene.add_light(cfgs["light"])
    scene.build()
    return scene


def worker(variant: str, warm: int) -> dict[str, Any]:
    """Time the imports, one cold build and ``warm`` warm builds, counting coacd runs."""
    start = time.perf_counter()
    import embodichain_core.sim.scene_build.convex as convex
    import embodichain_core.sim.scene  # noqa: F401

    import_s = time.perf_counter() - start
    calls = {"n": 0}
    run_coacd = convex._run_coacd

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls["n"] += 1
        return run_coacd(*args, **kwargs)

    convex._run_coacd = counted
    build, num_envs = _builder(variant)
    start = time.perf_counter()
    build()
    cold_s = time.perf_counter() - start
    cold_calls, warm_times = calls["n"], []
    for _ in range(warm):
        start = time.perf_counter()
        build()
        warm_times.append(time.perf_counter() - start)
    return {
        "variant": variant,
        "num_envs": num_envs,
        "import_s": import_s,
        "cold_s": cold_s,
        "warm_runs_s": warm_times,
        "coacd_calls_cold": cold_calls,
        "coacd_calls_warm": calls["n"] - cold_calls,
    }


# -- driver ---------------------------------------------------------------------------------------
def run_worker(variant: str, warm: int) -> dict[str, Any]:
    """One fresh process with an empty cache folder; returns its record or ``{"error": ...}``."""
    with tempfile.TemporaryDirectory(prefix="embodichain_cache_") as cache:
        env = dict(os.environ, EMBODICHAIN_CACHE_DIR=cache)
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", variant, "--warm", str(warm)]
        proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
    lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no output"]
        return {"variant": variant, "error": tail[0]}
    return json.loads(lines[-1])


def measure(variant: str, repeats: int, warm: int) -> dict[str, Any]:
    """Medians over ``repeats`` fresh processes of one variant."""
    runs = [run_worker(variant, warm) for _ in range(repeats)]
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return {"variant": variant, "skipped": runs[0]["error"]}
    return {
        "variant": variant,
        "num_envs": ok[0]["num_envs"],
        "import_s": median([r["import_s"] for r in ok]),
        "cold_s": median([r["cold_s"] for r in ok]),
        "warm_s": median([t for r in ok for t in r["warm_runs_s"]]),
        "coacd_calls_cold": ok[0]["coacd_calls_cold"],
        "coacd_calls_warm": max(r["coacd_calls_warm"] for r in ok),
        "cold_runs_s": [r["cold_s"] for r in ok],
        "warm_runs_s": [t for r in ok for t in r["warm_runs_s"]],
        "warm_target_met": median([t for r in ok for t in r["warm_runs_s"]]) < TARGET_WARM_S,
    }


def parse_args(argv: Optional[list[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes (cold builds) per variant")
    parser.add_argument("--warm", type=int, default=5, help="warm builds per process")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    parser.add_argument("--out", default=DEFAULT_OUT)
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    return parser.parse_args(argv)


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker, args.warm)))
        return {}
    records = []
    for variant in args.variants:
        rec = measure(variant, args.repeats, args.warm)
        records.append(rec)
        print(
            f"{variant:<20s} "
            + (
                f"skipped: {rec['skipped']}"
                if "skipped" in rec
                else f"cold {rec['cold_s']:.3f} s  warm {rec['warm_s']:.3f} s"
            ),
            flush=True,
        )
    payload = {
        "benchmark": "scene_build",
        "description": "Scene.build() time of the seed tutorial's scene (no robot, no camera), cold and warm",
        "settings": {
            "repeats": args.repeats,
            "warm_builds_per_process": args.warm,
            "target_warm_s": TARGET_WARM_S,
            "cold": "first build in a fresh process, EMBODICHAIN_CACHE_DIR = new empty folder",
            "warm": "later builds in the same process (coacd cache on disk)",
        },
        "machine": machine_info(),
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "results": records,
    }
    print()
    title = f"Scene build (median; cold over {args.repeats} processes, warm over {args.repeats * args.warm} builds)"
    print_table([r for r in records if "skipped" not in r], COLUMNS, title=title)
    print(f"\nwrote {write_json(args.out, payload)}")
    return payload


if __name__ == "__main__":
    main()
