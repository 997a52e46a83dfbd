"""Scenes and scripted runs shared by the embodichain-lerobot tests.

The scene is the core tests' inline 7-DoF arm (``tests/scenes.py``) with a cube;
``stereo_camera()`` adds a small stereo camera from embodichain-sensors. A
:class:`ScriptedEnv` succeeds or fails where the test says (``env.success_flags``).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Optional

import numpy as np
import torch

sys.path.append(str(Path(__file__).resolve().parents[3] / "tests"))

from scenes import seven_dof_arm_mjcf  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402
from embodichain_core.managers import DatasetFunctorCfg  # noqa: E402
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.shapes import CubeCfg  # noqa: E402

TASK = "Push the cube"
JOINTS = [f"joint{i}" for i in range(1, 8)]


class ScriptedEnv(EmbodiedEnv):
    """Per-env success/fail set by the test: ``env.success_flags[i] = True``."""

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        if "success_flags" not in self.__dict__:
            self.success_flags = torch.zeros(self.num_envs, dtype=torch.bool)
            self.fail_flags = torch.zeros(self.num_envs, dtype=torch.bool)
        return self.success_flags.clone(), self.fail_flags.clone(), {}


def stereo_camera(width: int = 32, height: int = 24, uid: str = "head", depth: bool = True, mask: bool = True) -> Any:
    """A stereo camera looking at the arm (needs embodichain-sensors)."""
    from embodichain_sensors.cfg import StereoCameraCfg

    return StereoCameraCfg(
        uid=uid,
        width=width,
        height=height,
        enable_depth=depth,
        enable_mask=mask,
        intrinsics=(width, width, width / 2, height / 2),
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(eye=(1.4, 0.0, 1.1), target=(0.2, 0.0, 0.3)),
    )


def recorder_cfg(save_path: Any, func: str = "LeRobotRecorder", save_failed: bool = False, **params: Any) -> dict:
    """A ``dataset`` section with one recorder named ``rec``."""
    base = {
        "save_path": str(save_path),
        "robot_meta": {"robot_type": "Arm7"},
        "instruction": {"lang": TASK},
        "extra": {"scene_type": "Table Top"},
    }
    return {"rec": DatasetFunctorCfg(func=func, params={**base, **params}, save_failed_episodes=save_failed)}


def arm_cfg(
    num_envs: int = 1, dataset: Optional[dict] = None, sensors: Optional[list] = None, **overrides: Any
) -> EmbodiedEnvCfg:
    """The 7-DoF arm (7 active joints) and a cube; 25 Hz control."""
    cfg = EmbodiedEnvCfg(
        num_envs=num_envs,
        seed=0,
        verbose=False,
        max_episode_steps=40,
        robot=RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]}),
        control_parts=["arm"],
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05, 0.05, 0.05]), init_pos=(0.5, 0, 0.05))],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="point", init_pos=(0.0, 0.0, 2.0))]),
        sensor=list(sensors or []),
        dataset=dataset,
    )
    for key, value in overrides.items():
        setattr(cfg, key, value)
    return cfg


def action_for(env: Any, step: int) -> torch.Tensor:
    """A deterministic, per-env different action of step ``step``."""
    n, a = env.action_space.shape
    base = torch.linspace(-0.2, 0.2, a)
    return (base[None, :] * (1 + 0.1 * step) + 0.01 * torch.arange(n)[:, None]).float()


def run_script(env: Any, script: list[list[str]], log: Optional[list] = None) -> None:
    """Step ``env`` once per script row; row[i] is env i's outcome: ``"s"`` success,
    ``"f"`` fail, ``"."`` nothing. ``log`` receives per step ``(obs_t, action)`` (numpy)."""
    obs = env.last_obs if hasattr(env, "last_obs") else None
    for t, row in enumerate(script):
        action = action_for(env, t)
        if log is not None:
            log.append((_np_tree(obs), action.numpy().copy()))
        env.success_flags[:] = torch.tensor([c == "s" for c in row])
        env.fail_flags[:] = torch.tensor([c == "f" for c in row])
        obs, *_ = env.step(action)
        env.success_flags[:] = False
        env.fail_flags[:] = False
        env.last_obs = obs


def reset(env: Any) -> Any:
    """Reset every env, remembering the observation for :func:`run_script`."""
    obs, _ = env.reset()
    env.last_obs = obs
    return obs


def _np_tree(obs: Any) -> Any:
    if isinstance(obs, dict):
        return {k: _np_tree(v) for k, v in obs.items()}
    return obs.detach().cpu().numpy().copy() if isinstance(obs, torch.Tensor) else obs


def expected_episodes(script: list[list[str]], log: list, num_envs: int) -> list[tuple[int, list]]:
    """(env id, [(obs_t, action_t) rows of env i]) of each successful episode, in commit order."""
    starts, out = [0] * num_envs, []
    for t, row in enumerate(script):
        for i, c in enumerate(row):
            if c in "sf":
                if c == "s":
                    out.append((i, [(_row(log[k][0], i), log[k][1][i]) for k in range(starts[i], t + 1)]))
                starts[i] = t + 1
    return out


def _row(tree: Any, i: int) -> Any:
    if isinstance(tree, dict):
        return {k: _row(v, i) for k, v in tree.items()}
    return tree[i]


def load(path: Any) -> Any:
    """The dataset at ``path`` through ``LeRobotDataset`` (offline)."""
    from embodichain_lerobot.reading import load_dataset

    return load_dataset(path)


def episode_items(ds: Any, episode: int) -> list[dict]:
    """Every frame (``ds[i]`` dict) of ``episode``."""
    ep = ds.meta.episodes[episode]
    return [ds[i] for i in range(ep["dataset_from_index"], ep["dataset_to_index"])]


def as_np(value: Any) -> np.ndarray:
    return value.numpy() if hasattr(value, "numpy") else np.asarray(value)


def have_sensors() -> bool:
    try:
        import embodichain_sensors  # noqa: F401
    except ImportError:
        return False
    return True


def datasets_under(root: Any) -> list[Path]:
    return sorted(p for p in Path(root).iterdir() if p.is_dir())
