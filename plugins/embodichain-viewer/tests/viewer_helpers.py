"""Helpers of the viewer tests: the demo scene with a camera (and a recorder), free ports,
waiting for a viewer to draw."""

from __future__ import annotations

import socket
import time
from pathlib import Path
from typing import Any, Callable, Optional

import torch


def free_port() -> int:
    """A localhost port nobody listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def demo_env(viewer: str = "none", port: int = 0, dataset: Optional[Path] = None, num_envs: int = 2) -> Any:
    """The built-in demo scene with a 32x24 camera (colour and depth); ``viewer`` other than
    ``"none"`` builds it with ``headless: false``; ``dataset``: record there (LeRobotRecorder)."""
    from embodichain_core.cli.run_env import RunPlan, make_env
    from embodichain_core.config.loader import load_config_file, load_gym_config, resolve_relative_paths
    from embodichain_core.demo import DEMO_CONFIG

    data = load_config_file(str(DEMO_CONFIG))
    resolve_relative_paths(data, str(Path(DEMO_CONFIG).parent))
    data["sensor"] = [
        {
            "sensor_type": "Camera",
            "uid": "cam",
            "width": 32,
            "height": 24,
            "enable_depth": True,
            "extrinsics": {"eye": [1.4, 0.0, 1.1], "target": [0.2, 0.0, 0.3]},
        }
    ]
    data["num_envs"] = num_envs
    data["env"]["verbose"] = False
    if dataset is not None:
        data["env"]["dataset"] = {
            "lerobot": {
                "func": "LeRobotRecorder",
                "save_failed_episodes": True,
                "params": {
                    "save_path": str(dataset),
                    "robot_meta": {"robot_type": "arm7"},
                    "instruction": {"lang": "move"},
                    "extra": {"scene_type": "table", "task_description": "move"},
                },
            }
        }
    overrides: dict = {"headless": viewer == "none"}
    if viewer != "none":
        overrides.update(viewer=viewer, viewer_port=port)
    task_id, cfg, extras = load_gym_config(data, overrides)
    return make_env(RunPlan(task_id, cfg, extras))


def action(env: Any, k: int) -> torch.Tensor:
    """A deterministic action: the joint targets swing with ``k``."""
    low = torch.as_tensor(env.unwrapped.single_action_space.low)
    high = torch.as_tensor(env.unwrapped.single_action_space.high)
    frac = 0.5 + 0.4 * torch.sin(torch.arange(low.shape[0]) + 0.3 * k)
    return (low + frac * (high - low)).expand(env.unwrapped.num_envs, -1).clone()


def wait_for(predicate: Callable[[], bool], what: str, limit_s: float = 20.0) -> None:
    """Poll ``predicate`` until true; fail naming ``what`` after ``limit_s`` (a hang guard)."""
    end = time.monotonic() + limit_s
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"gave up waiting for {what}")
        time.sleep(0.02)
