"""Timing and batch-size resolution of an env config."""

from __future__ import annotations

import math
from typing import Any

from embodichain_core.config.errors import ConfigError


def resolve_timing(cfg: Any) -> tuple[float, int]:
    """Return ``(physics_dt, sim_steps_per_control)``; validate and write back."""
    dt = cfg.sim_cfg.physics_dt
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not math.isfinite(dt) or dt <= 0:
        raise ConfigError("sim_cfg.physics_dt", f"must be a finite number > 0, got {dt!r}")
    steps = cfg.sim_steps_per_control
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ConfigError("sim_steps_per_control", f"must be a positive int, got {steps!r}")
    freq = cfg.target_control_frequency
    if freq is not None:
        if isinstance(freq, bool) or not math.isfinite(float(freq)) or float(freq) <= 0:
            raise ConfigError("target_control_frequency", f"must be a finite number > 0, got {freq!r}")
        exact = 1.0 / (dt * float(freq))
        steps = round(exact)
        if steps < 1 or abs(exact - steps) > 1e-9 * max(1.0, exact):
            raise ConfigError(
                "target_control_frequency",
                f"{freq} Hz cannot be represented exactly with physics_dt={dt} "
                f"(would need {exact:.6g} physics steps per control step)",
            )
        cfg.sim_steps_per_control = steps
    return float(dt), int(steps)


def resolve_num_envs(cfg: Any, override: Any = None) -> int:
    """``num_envs`` from (in order) an explicit override, ``cfg.num_envs``, or
    ``cfg.sim_cfg.num_envs`` (the seed tutorial sets it there)."""
    n = override if override is not None else cfg.num_envs
    sim_n = cfg.sim_cfg.num_envs
    if override is None and n == 1 and sim_n != 1:
        n = sim_n
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ConfigError("num_envs", f"must be a positive int, got {n!r}")
    if override is None and sim_n not in (1, n):
        raise ConfigError("num_envs", f"num_envs={n} disagrees with sim_cfg.num_envs={sim_n}")
    cfg.num_envs = cfg.sim_cfg.num_envs = n
    return n
