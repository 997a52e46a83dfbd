"""Helpers of the embodichain-tasks tests: paths, small configs, config comparison, a CLI runner."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Sequence

PLUGIN = Path(__file__).resolve().parents[1]
REPO = PLUGIN.parents[1]
#: Tasks of this plugin owned by these tests (the IL tasks have their own test files).
MY_TASKS = ("ModularEnv-v1", "PushCube-v1")


def small_stereo(cfg: Any, width: int = 96, height: int = 54) -> Any:
    """``cfg`` with its stereo camera at ``width`` x ``height`` (intrinsics scaled alike)."""
    cfg = cfg.copy()
    for sensor in cfg.sensor:
        scale = width / sensor.width
        fx, fy, cx, cy = sensor.intrinsics
        sensor.intrinsics = (fx * scale, fy * scale, cx * scale, cy * scale)
        if getattr(sensor, "intrinsics_right", None) is not None:
            fx, fy, cx, cy = sensor.intrinsics_right
            sensor.intrinsics_right = (fx * scale, fy * scale, cx * scale, cy * scale)
        sensor.width, sensor.height = width, height
    return cfg


def run_cli(command: Sequence[str], timeout: float = 300.0) -> subprocess.CompletedProcess:
    """Run ``command`` from the repository root; fail with its output on a non-zero exit."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    out = subprocess.run(list(command), cwd=REPO, capture_output=True, text=True, timeout=timeout, env=env)
    assert out.returncode == 0, (
        f"{' '.join(command)} exited {out.returncode}:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    )
    return out


def embodichain_command() -> list[str]:
    """The ``embodichain`` console script of this interpreter's environment (or ``python -m``)."""
    script = Path(sys.executable).with_name("embodichain")
    return [str(script)] if script.exists() else [sys.executable, "-m", "embodichain_core.cli.main"]


_PATH_KEYS = ("fpath", "folder_path", "texture_path")
_KINDS = {"events": "event", "observations": "observation", "rewards": "reward", "actions": "action"}
#: Run-level and simulation fields a gym config sets for the CLI (not part of the scene).
_RUN_FIELDS = ("sim_cfg", "num_envs", "seed", "verbose", "max_episode_steps")


def normalized_cfg(cfg: Any) -> dict:
    """A comparable form of an ``EmbodiedEnvCfg``: data paths resolved, functors resolved
    to their callables, ``articulation_cfg`` merged into ``articulation``, run-level fields
    and the robot's ``class_type`` dropped, entity configs reduced to their set fields."""
    from embodichain_core.managers.manager_base import resolve_func

    data = cfg.to_dict()
    data["articulation"] = list(data["articulation"]) + list(data.pop("articulation_cfg"))
    for key in _RUN_FIELDS:
        data.pop(key, None)
    data["robot"].pop("class_type", None)
    for section, kind in _KINDS.items():
        for name, fcfg in (data.get(section) or {}).items():
            fcfg["func"] = resolve_func(fcfg["func"], kind, f"{section}.{name}")
    return _normalize(data)


def _normalize(node: Any) -> Any:
    from embodichain_core.sim.data import get_data_path

    if isinstance(node, dict):
        if "uid" in node and set(node) <= {
            "uid",
            "joint_names",
            "joint_ids",
            "link_names",
            "control_parts",
            "body_names",
            "body_ids",
            "preserve_order",
        }:
            return {k: v for k, v in node.items() if v not in (None, False)}
        return {
            k: (os.path.realpath(get_data_path(v)) if k in _PATH_KEYS and isinstance(v, str) else _normalize(v))
            for k, v in node.items()
        }
    if isinstance(node, (list, tuple)):
        return [_normalize(v) for v in node]
    return node
