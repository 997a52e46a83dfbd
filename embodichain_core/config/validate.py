"""Whole-config validation at build: run settings, simulation, scene, managers, memory.

:func:`validate_env_cfg` is what ``EmbodiedEnvCfg.validate()`` runs (the env calls
it first thing when it builds its scene), so every bad value is a
:class:`~embodichain_core.config.errors.ConfigError` naming its config path before
MuJoCo compiles anything or a buffer is allocated. The rules are listed in
docs/configuration.md ("Validated values").

Example:
    >>> validate_env_cfg(cfg)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Optional

from embodichain_core.config.checks import check_int, check_number, check_vector
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.config.joint_check import check_robot_joints
from embodichain_core.config.physical import check_scene
from embodichain_core.config.plausible import check_plausible
from embodichain_core.config.resources import MAX_NUM_ENVS, check_memory
from embodichain_core.config.sections import check_sections
from embodichain_core.utils.suggest import did_you_mean

__all__ = [
    "validate_env_cfg",
    "check_run_settings",
    "check_sim",
    "check_backend",
    "check_cuda_device",
    "MAX_SIM_STEPS_PER_CONTROL",
    "MAX_PHYSICS_SUBSTEPS",
    "MAX_EPISODE_STEPS",
    "MAX_PHYSICS_DT",
]

MAX_SIM_STEPS_PER_CONTROL = 10_000
MAX_PHYSICS_SUBSTEPS = 1_000
MAX_EPISODE_STEPS = 100_000_000
#: Largest physics step (seconds); MuJoCo is unstable far below this already.
MAX_PHYSICS_DT = 1.0
_MAX_SIDE = 16384


def validate_env_cfg(cfg: Any, num_envs: Optional[int] = None, *, memory: bool = True, functors: bool = True) -> None:
    """Check an ``EmbodiedEnvCfg`` completely; ``memory=False`` skips the memory estimate.

    Args:
        cfg: the config (required values already set).
        num_envs: the env count to check the memory for (default ``cfg.num_envs``).
        memory: compare the memory estimate with the available memory.
        functors: check the manager sections (the env's build checks them itself with
            :func:`~embodichain_core.config.sections.check_sections`, which returns each
            functor resolved for the build).

    Raises:
        ConfigError: the first bad value, at its config path.
    """
    check_run_settings(cfg, num_envs)
    check_sim(cfg.sim_cfg, "sim_cfg")
    check_scene(cfg)
    check_plausible(cfg)
    check_robot_joints(cfg.robot, "robot")
    if functors:
        check_sections(cfg)
    if memory:
        check_memory(cfg, num_envs)


def check_run_settings(cfg: Any, num_envs: Optional[int] = None) -> None:
    """``num_envs``, ``sim_steps_per_control``, ``max_episode_steps`` (``<= 0``:
    unlimited), ``seed``, ``control_parts``/``active_joint_ids`` and the flags."""
    hint = " (each env is a separate MuJoCo simulation)"
    check_int(cfg.num_envs if num_envs is None else num_envs, "num_envs", low=1, high=MAX_NUM_ENVS, hint=hint)
    check_int(cfg.sim_steps_per_control, "env.sim_steps_per_control", low=1, high=MAX_SIM_STEPS_PER_CONTROL)
    check_int(
        cfg.max_episode_steps, "max_episode_steps", low=-(2**31), high=MAX_EPISODE_STEPS, hint=" (0 or less: unlimited)"
    )
    if cfg.target_control_frequency is not None:
        check_number(cfg.target_control_frequency, "env.target_control_frequency", low=0.0, low_open=True)
    if cfg.seed is not None:
        check_int(cfg.seed, "env.seed", low=-1, high=2**63 - 1)
    for name in (
        "ignore_terminations",
        "verbose",
        "filter_visual_rand",
        "filter_dataset_saving",
        "init_rollout_buffer",
        "strict_actions",
    ):
        if not isinstance(getattr(cfg, name, False), bool):
            raise ConfigError(join_path("env", name), f"expected true/false, got {getattr(cfg, name)!r}")
    for i, jid in enumerate(getattr(cfg, "active_joint_ids", None) or []):
        check_int(jid, f"env.active_joint_ids[{i}]", low=0)
    parts = getattr(cfg, "control_parts", None)
    if parts is not None and (isinstance(parts, str) or not all(isinstance(p, str) and p for p in parts)):
        raise ConfigError("env.control_parts", f"expected a list of control part names, got {parts!r}")


def check_backend(sim: Any, path: str) -> None:
    """``backend`` is one of the simulation backends; ``warp`` runs on cpu or cuda[:N] and
    not with the PGS solver (MuJoCo Warp has none)."""
    from embodichain_core.sim.cfg import BACKENDS as backends

    backend = getattr(sim, "backend", "mujoco_batch")
    if backend not in backends:
        raise ConfigError(
            join_path(path, "backend"), f"unknown backend {backend!r}.{did_you_mean(str(backend), backends)}"
        )
    if backend != "warp":
        return
    device = str(sim.sim_device)
    if not (device == "cpu" or device == "cuda" or (device.startswith("cuda:") and device[5:].isdigit())):
        raise ConfigError(
            join_path(path, "sim_device"),
            f"{device!r} is not a device of backend 'warp'; use 'cpu', 'cuda' or 'cuda:N'",
        )
    if device != "cpu":
        check_cuda_device(device, join_path(path, "sim_device"))
    if sim.physics_config.solver == "PGS":
        raise ConfigError(
            join_path(path, "physics_config", "solver"),
            "'PGS' is not available on backend 'warp'; use 'Newton' or 'CG'",
        )


def check_cuda_device(device: str, path: str) -> None:
    """``cuda`` / ``cuda:N`` names a GPU torch sees (checked before anything is built)."""
    import torch

    count = torch.cuda.device_count() if torch.cuda.is_available() else 0
    index = int(device[5:]) if device.startswith("cuda:") else 0
    if index < count:
        return
    have = "no CUDA GPU" if not count else f"{count} CUDA GPU(s) (cuda:0 to cuda:{count - 1})"
    choice = "'cpu' (Warp's CPU device: the same code, slower)" if not count else "'cuda:0'"
    raise ConfigError(path, f"{device!r}: this machine has {have}; use {choice}")


def check_sleep(sim: Any, where: str) -> None:
    """``enable_sleep`` (MuJoCo's sleeping islands) needs a persistent ``mujoco_batch``."""
    if not isinstance(sim.physics_config.enable_sleep, bool):
        raise ConfigError(
            join_path(where, "enable_sleep"), f"expected true/false, got {sim.physics_config.enable_sleep!r}"
        )
    if not sim.physics_config.enable_sleep:
        return
    if getattr(sim, "backend", "mujoco_batch") == "warp":
        raise ConfigError(join_path(where, "enable_sleep"), "sleeping is not available on backend 'warp'")
    if not sim.persistent:
        raise ConfigError(
            join_path(where, "enable_sleep"), "sleeping needs a persistent batch (sim_cfg.persistent: true)"
        )


def check_sim(sim: Any, path: str) -> None:
    """``SimulationManagerCfg``: time step, substeps, solver, gravity, window and render sizes."""
    check_number(
        sim.physics_dt, join_path(path, "physics_dt"), low=0.0, high=MAX_PHYSICS_DT, low_open=True, what="seconds"
    )
    check_int(sim.physics_substeps, join_path(path, "physics_substeps"), low=1, high=MAX_PHYSICS_SUBSTEPS)
    check_number(sim.arena_space, join_path(path, "arena_space"), low=0.0)
    for name in ("width", "height"):
        check_int(getattr(sim, name), join_path(path, name), low=1, high=_MAX_SIDE)
    for name in ("gpu_id", "thread_mode", "cpu_num"):
        check_int(getattr(sim, name), join_path(path, name), low=0, high=4096)
    check_backend(sim, path)
    phys, where = sim.physics_config, join_path(path, "physics_config")
    check_sleep(sim, where)
    check_vector(phys.gravity, 3, join_path(where, "gravity"), what="m/s^2")
    check_int(phys.iterations, join_path(where, "iterations"), low=1, high=10_000)
    for name in ("bounce_threshold", "length_tolerance", "speed_tolerance"):
        check_number(getattr(phys, name), join_path(where, name), low=0.0)
    render = join_path(path, "render_cfg")
    check_int(sim.render_cfg.spp, join_path(render, "spp"), low=1, high=4096)
    check_number(
        sim.render_cfg.tone_mapping_exposure, join_path(render, "tone_mapping_exposure"), low=0.0, low_open=True
    )
