"""The main job case of ``record_throughput.py``: ``make run``'s config, recorded vs not.

Each twin runs in its own process (so the recorded one pays its imports in its
build time, as ``embodichain run-env`` does): the main job's gym config
(``embodichain_tasks/configs/main_job.json``: 2 envs, 320x180 stereo camera,
scripted demos, ``AsyncLeRobotRecorder`` with its writer process and h264 videos) with ``save_path`` pointed at a
temporary folder and seed 0 (every run draws the same scenes), and its unrecorded twin (``filter_dataset_saving``). Each child
prints one JSON line: build time, run time (the episode loop), close time (the
final flush: the recorder finalizes) and env steps. Reported per twin:

* ``env_steps_per_s``: env steps over the run time (what ``run-env`` prints);
* ``end_to_end_steps_per_s``: env steps over run + close time;
* ``ratio``: recorded end-to-end over the unrecorded twin's (the issue-21 target is >= 0.8);
* ``build_s``: building the env (the target: recorded within 0.5 s of unrecorded);
* with ``--case main_job_depth_masks`` in ``record_throughput.py``: the dataset size with
  depth and masks over the size without (target <= 3), with the main job's H.264 colour and
  with lerobot's default AV1 (``size_ratio_libsvtav1``) and the wall times of
  ``embodichain dataset preview`` (PNG sheet target <= 3 s, mp4 <= 10 s);
* ``cpu_s`` (per run): CPU seconds of the run and close, all threads (steadier than
  wall time on a shared machine); ``writer_process_cpu_s``: those of the recorder's writer
  process (its whole life: lerobot's import included).

Usage (normally through ``record_throughput.py --case main_job``):
    python benchmarks/record_main_job.py --child recorded|unrecorded --save-path DIR [--episodes K]
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

TWINS = ("unrecorded", "recorded")


def main_job_config() -> str:
    """Path of the main job's gym config (from the installed embodichain-tasks plugin)."""
    import importlib.util

    spec = importlib.util.find_spec("embodichain_tasks")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit(
            "the main job case needs the embodichain-tasks plugin (pip install -e plugins/embodichain-tasks)"
        )
    return os.path.join(list(spec.submodule_search_locations)[0], "configs", "main_job.json")


def _child(
    twin: str,
    save_path: str,
    episodes: int,
    params: Optional[dict] = None,
    func: Optional[str] = None,
    depth_masks: bool = False,
) -> dict[str, Any]:
    from embodichain_core.cli.run_env import build_parser, prepare
    from embodichain_core.cli.run_loops import RunStats, make_env, run_episodes

    with open(main_job_config(), encoding="utf-8") as f:
        cfg = json.load(f)
    cfg["env"]["dataset"]["lerobot"]["params"].update({"save_path": save_path, **(params or {})})
    if func:
        cfg["env"]["dataset"]["lerobot"]["func"] = func
    for sensor in cfg["sensor"] if depth_masks else ():
        sensor.update(enable_depth=True, enable_mask=True)
    cfg_path = os.path.join(save_path, "main_job.json")
    os.makedirs(save_path, exist_ok=True)
    with open(cfg_path, "w", encoding="utf-8") as f:
        json.dump(cfg, f)
    argv = ["--gym_config", cfg_path, "--headless", "--quiet", "--max_episodes", str(episodes), "--seed", "0"]
    plan = prepare(build_parser().parse_args(argv + (["--filter_dataset_saving"] if twin == "unrecorded" else [])))
    started = time.perf_counter()
    env = make_env(plan)
    build_s = time.perf_counter() - started
    stats = RunStats()
    cpu = time.process_time()
    run_episodes(env, plan.extras, stats)
    started = time.perf_counter()
    env.close()
    close_s = time.perf_counter() - started
    paths = [str(p) for p in env.unwrapped.dataset_manager.finalize() if p] if twin == "recorded" else []
    return {
        "twin": twin,
        "build_s": build_s,
        "run_s": stats.run_s,
        "close_s": close_s,
        "cpu_s": time.process_time() - cpu,
        "writer_process_cpu_s": _children_cpu(),
        "env_steps": stats.env_steps,
        "episodes": stats.episodes,
        "saved": stats.saved,
        "dataset": paths[0] if paths else None,
    }


def _children_cpu() -> float:
    """CPU seconds of this process's finished children (the recorder's writer process)."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_twin(
    twin: str, episodes: int, workdir: str, depth_masks: bool = False, params: Optional[dict] = None
) -> dict[str, Any]:
    """Run one twin in a child process (``params``: recorder params to override); its JSON result."""
    save_path = tempfile.mkdtemp(prefix=f"{twin}_", dir=workdir)
    cmd = (
        [
            sys.executable,
            os.path.abspath(__file__),
            "--child",
            twin,
            "--save-path",
            save_path,
            "--episodes",
            str(episodes),
        ]
        + (["--depth-masks"] if depth_masks else [])
        + (["--params", json.dumps(params)] if params else [])
    )
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("{")][-1]
    return json.loads(line)


def measure_main_job(episodes: int, repeats: int, workdir: str) -> dict[str, Any]:
    """Both twins, interleaved, ``repeats`` times; medians of the rates."""
    runs: dict[str, list[dict]] = {t: [] for t in TWINS}
    for _ in range(max(1, repeats)):
        for twin in TWINS:
            runs[twin].append(run_twin(twin, episodes, workdir))
    record: dict[str, Any] = {"case": "main_job", "episodes": episodes, "repeats": repeats, "contenders": {}}
    base: Optional[float] = None
    for twin in TWINS:
        rs = runs[twin]
        sps = sorted(r["env_steps"] / r["run_s"] for r in rs)[len(rs) // 2]
        e2e = sorted(r["env_steps"] / (r["run_s"] + r["close_s"]) for r in rs)[len(rs) // 2]
        base = e2e if base is None else base
        record["contenders"][twin] = {
            "env_steps_per_s": sps,
            "end_to_end_steps_per_s": e2e,
            "ratio": e2e / base,
            "build_s": sorted(r["build_s"] for r in rs)[len(rs) // 2],
            "runs": rs,
            "episodes_saved": rs[-1]["saved"],
        }
    return record


def _size(path: str) -> int:
    return sum(os.path.getsize(os.path.join(d, f)) for d, _, files in os.walk(path) for f in files)


def _timed(cmd: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - started


def measure_depth_masks(episodes: int, workdir: str) -> dict[str, Any]:
    """The main job recorded with and without depth and masks: dataset sizes, and
    ``embodichain dataset preview`` wall times (PNG sheet, mp4) of episode 0 with them."""
    plain = run_twin("recorded", episodes, workdir)["dataset"]
    full = run_twin("recorded", episodes, workdir, depth_masks=True)["dataset"]
    av1 = {"vcodec": "libsvtav1"}  # lerobot's default codec: colour about twice the main job's H.264 size
    plain_av1 = run_twin("recorded", episodes, workdir, params=av1)["dataset"]
    full_av1 = run_twin("recorded", episodes, workdir, depth_masks=True, params=av1)["dataset"]
    cli = [
        os.path.join(os.path.dirname(sys.executable), "embodichain"),
        "dataset",
        "preview",
        full,
        "--episode",
        "0",
        "--out",
        os.path.join(workdir, "preview"),
    ]
    record: dict[str, Any] = {
        "case": "main_job_depth_masks",
        "episodes": episodes,
        "bytes_without": _size(plain),
        "bytes_with": _size(full),
        "preview_png_s": _timed(cli),
        "preview_mp4_s": _timed(cli + ["--format", "mp4"]),
    }
    record["size_ratio"] = record["bytes_with"] / record["bytes_without"]
    record["size_ratio_libsvtav1"] = _size(full_av1) / _size(plain_av1)
    return record


def _parse(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--child", choices=TWINS, required=True)
    p.add_argument("--save-path", required=True)
    p.add_argument("--episodes", type=int, default=4)
    p.add_argument("--params", default="{}", help="JSON: recorder params to override (e.g. vcodec)")
    p.add_argument("--func", default=None, help="recorder functor instead of the config's (e.g. LeRobotRecorder)")
    p.add_argument("--depth-masks", action="store_true", help="also record the camera's depth and masks")
    return p.parse_args(argv)


if __name__ == "__main__":
    args = _parse()
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("SVT_LOG", "1")
    print(
        json.dumps(
            _child(args.child, args.save_path, args.episodes, json.loads(args.params), args.func, args.depth_masks)
        )
    )
