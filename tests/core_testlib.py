"""Shared helpers and fixtures of the core tests (a uniquely named module: the test
directories of the plugins share sys.path and each has its own ``conftest``)."""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, Iterator

import pytest
import torch

if os.path.dirname(__file__) not in sys.path:
    sys.path.insert(0, os.path.dirname(__file__))

from scenes import seven_dof_arm_mjcf  # noqa: E402

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg  # noqa: E402
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.shapes import CubeCfg  # noqa: E402

CUBE_INIT = (0.5, 0.0, 0.05)
TABLE_INIT = (0.0, 0.8, 0.2)
ARM_ACTIVE = 7
ARM_DOF = 9


def base_cfg(**overrides: Any) -> EmbodiedEnvCfg:
    """The small default scene (see module docstring) with ``overrides`` applied."""
    cfg = EmbodiedEnvCfg(
        num_envs=2,
        seed=0,
        verbose=False,
        robot=RobotCfg(uid="arm", mjcf=seven_dof_arm_mjcf(), control_parts={"arm": ["joint[1-7]"]}),
        control_parts=["arm"],
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05, 0.05, 0.05]), init_pos=CUBE_INIT)],
        background=[
            RigidObjectCfg(uid="table", shape=CubeCfg(size=[0.4, 0.4, 0.4]), init_pos=TABLE_INIT, body_type="kinematic")
        ],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="point", init_pos=(0.0, 0.0, 2.0))]),
    )
    for key, value in overrides.items():
        if key not in cfg.__dataclass_fields__:
            raise AttributeError(f"EmbodiedEnvCfg has no field {key!r}")
        setattr(cfg, key, value)
    return cfg


@pytest.fixture
def make_cfg() -> Callable[..., EmbodiedEnvCfg]:
    """Factory: ``make_cfg(**overrides) -> EmbodiedEnvCfg``."""
    return base_cfg


@pytest.fixture
def make_env() -> Iterator[Callable[..., EmbodiedEnv]]:
    """Factory: ``make_env(cfg=None, env_cls=EmbodiedEnv, **cfg_overrides)``; envs are closed after the test."""
    envs: list[EmbodiedEnv] = []

    def make(cfg: EmbodiedEnvCfg | None = None, env_cls: type = EmbodiedEnv, **overrides: Any) -> EmbodiedEnv:
        env = env_cls(cfg if cfg is not None else base_cfg(**overrides))
        envs.append(env)
        return env

    yield make
    for env in envs:
        try:
            env.close()
        except Exception:  # a test may have broken its env on purpose
            pass


def zero_action(env: EmbodiedEnv) -> torch.Tensor:
    """A zero action of the env's (batched) action space shape."""
    return torch.zeros(env.action_space.shape, dtype=torch.float32)


class FlagEnv(EmbodiedEnv):
    """An env whose per-env success/fail the test sets: ``env.success_flags[i] = True``."""

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        if "success_flags" not in self.__dict__:
            self.success_flags = torch.zeros(self.num_envs, dtype=torch.bool)
            self.fail_flags = torch.zeros(self.num_envs, dtype=torch.bool)
        return self.success_flags.clone(), self.fail_flags.clone(), {"steps": self._elapsed_steps.clone()}


def call_log(env: Any) -> list:
    """A per-env-instance list the fixture functors append their calls to."""
    return env.__dict__.setdefault("call_log", [])


def ids_list(env_ids: Any) -> Any:
    """``env_ids`` as a plain list (``None`` stays ``None``)."""
    if env_ids is None:
        return None
    return torch.as_tensor(env_ids).reshape(-1).tolist()


def audited_push_cube(actions: Any = None) -> Iterator[tuple[Any, Any]]:
    """PushCube-v1 on backend warp (Warp's CPU device, 2 envs), built and reset inside a
    :class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit` (so it takes the device
    code paths and the audit knows its tensors); ``actions`` replaces the task's action terms.
    A generator for module fixtures: yields ``(env, audit)``, closes the env after."""
    import gymnasium as gym

    import embodichain_core  # noqa: F401  (loads the plugins: PushCube-v1)
    from embodichain_core.sim.backend.device_audit import HostWaitAudit
    from embodichain_tasks.rl.push_cube import PushCubeCfg

    cfg = PushCubeCfg()
    cfg.sim_cfg.backend = "warp"
    cfg.sim_cfg.sim_device = "cpu"
    if actions is not None:
        cfg.actions = actions
    audit = HostWaitAudit("cpu")
    with audit:
        env = gym.make("PushCube-v1", cfg=cfg, num_envs=2, seed=0, verbose=False).unwrapped
        env.reset(seed=0)
        try:
            yield env, audit
        finally:
            env.close()
