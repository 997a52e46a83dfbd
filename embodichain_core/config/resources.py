"""Memory estimate of an env config, checked before anything is allocated.

The estimate adds, for ``num_envs`` envs:

* the simulations: :data:`SIM_BYTES_PER_ENV` per env plus :data:`SIM_BYTES_PER_ENTITY`
  per configured entity (MuJoCo's per-env state and the batch's views; the
  arena MuJoCo reserves is virtual memory, touched only as contacts need it).
  Measured on the main job's W1 scene (5 entities): 0.32 MB per env after 20
  steps; the estimate is 0.48 MB;
* every sensor's buffers: a sensor config reports ``buffer_bytes_per_env()``
  (a camera: height x width x bytes per pixel of each enabled output, twice for
  a stereo pair), counted twice (the render buffers and the observation);
* the rollout buffer when one is kept (``init_rollout_buffer``): every
  observation of every step of an episode.

A config whose estimate exceeds the available memory (``MemAvailable`` of
/proc/meminfo, or psutil) fails with the estimate and the fields to change. The
env var ``EMBODICHAIN_MEMORY_LIMIT_GB`` replaces the available memory (a larger
value lets a run go ahead anyway; ``0`` disables the check).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Optional

from embodichain_core.config.checks import check_int
from embodichain_core.config.errors import ConfigError

__all__ = [
    "MemoryEstimate",
    "estimate_memory",
    "available_memory",
    "check_memory",
    "MEMORY_LIMIT_ENV",
    "MAX_NUM_ENVS",
    "SIM_BYTES_PER_ENV",
    "SIM_BYTES_PER_ENTITY",
]

MEMORY_LIMIT_ENV = "EMBODICHAIN_MEMORY_LIMIT_GB"
#: Largest ``num_envs`` accepted whatever the memory (each env is a MuJoCo simulation).
MAX_NUM_ENVS = 1_000_000
SIM_BYTES_PER_ENV = 256 * 1024
SIM_BYTES_PER_ENTITY = 48 * 1024
_GB = 1024**3


@dataclass
class MemoryEstimate:
    """Bytes per part (``{"simulation": ..., "sensor[0] (StereoCamera)": ...}``) and the
    config fields that scale each part."""

    parts: dict[str, int] = field(default_factory=dict)
    fields: dict[str, list[str]] = field(default_factory=dict)

    @property
    def total(self) -> int:
        return sum(self.parts.values())

    def largest(self) -> str:
        """The name of the largest part."""
        return max(self.parts, key=self.parts.__getitem__)

    def describe(self) -> str:
        """``"simulation 1.2 GB, sensor[0] (StereoCamera) 3.4 GB"``."""
        return ", ".join(f"{name} {_gb(size)}" for name, size in sorted(self.parts.items(), key=lambda kv: -kv[1]))


def _gb(size: float) -> str:
    return f"{size / _GB:.3g} GB" if size >= 0.01 * _GB else f"{size / 1024**2:.3g} MB"


def _entity_count(cfg: Any) -> int:
    groups = sum(max(len(g.rigid_objects), int(g.max_num)) for g in cfg.rigid_object_group)
    return (
        1
        + len(cfg.all_articulations())
        + len(cfg.rigid_object)
        + len(cfg.background)
        + groups
        + len(cfg.light.direct)
        + len(cfg.sensor)
    )


def estimate_memory(cfg: Any, num_envs: Optional[int] = None) -> MemoryEstimate:
    """Estimate the memory an ``EmbodiedEnvCfg`` needs (see the module docstring)."""
    n = int(cfg.num_envs if num_envs is None else num_envs)
    est = MemoryEstimate()
    est.parts["simulation"] = n * (SIM_BYTES_PER_ENV + SIM_BYTES_PER_ENTITY * _entity_count(cfg))
    est.fields["simulation"] = ["num_envs"]
    per_env_obs = 0
    for i, sensor in enumerate(cfg.sensor):
        hook = getattr(sensor, "buffer_bytes_per_env", None)
        if not callable(hook):
            continue
        size = int(hook())
        per_env_obs += size
        name = f"sensor[{i}] ({type(sensor).__name__.removesuffix('Cfg')})"
        est.parts[name] = 2 * n * size
        est.fields[name] = ["num_envs", f"sensor[{i}].width", f"sensor[{i}].height", f"sensor[{i}].enable_*"]
    if getattr(cfg, "init_rollout_buffer", False) and int(cfg.max_episode_steps) > 0:
        est.parts["rollout buffer"] = n * int(cfg.max_episode_steps) * (per_env_obs + 4096)
        est.fields["rollout buffer"] = ["num_envs", "max_episode_steps", "init_rollout_buffer", "sensor sizes"]
    return est


def available_memory() -> tuple[Optional[int], str]:
    """``(bytes, source)``: the memory a config may use, ``None`` when unknown or disabled."""
    override = os.environ.get(MEMORY_LIMIT_ENV, "").strip()
    if override:
        try:
            value = float(override)
        except ValueError:
            raise ConfigError("", f"{MEMORY_LIMIT_ENV}={override!r} is not a number of GB") from None
        return (int(value * _GB) if value > 0 else None), f"{MEMORY_LIMIT_ENV}={override}"
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024, "available memory"
    except OSError:
        pass
    try:
        import psutil

        return int(psutil.virtual_memory().available), "available memory"
    except Exception:  # psutil missing or unsupported platform: no check
        return None, "unknown"


def check_memory(cfg: Any, num_envs: Optional[int] = None) -> MemoryEstimate:
    """Fail when ``cfg`` would need more memory than is available.

    Raises:
        ConfigError: at the field that scales the largest part, with the estimate,
            the limit and the fields to change.
    """
    n = check_int(
        cfg.num_envs if num_envs is None else num_envs,
        "num_envs",
        low=1,
        high=MAX_NUM_ENVS,
        hint=" (each env is a separate MuJoCo simulation)",
    )
    est = estimate_memory(cfg, n)
    limit, source = available_memory()
    if limit is None or est.total <= limit:
        return est
    largest = est.largest()
    fields = ", ".join(est.fields[largest])
    raise ConfigError(
        est.fields[largest][0] if largest == "simulation" else _path_of(largest),
        f"num_envs={n} needs about {_gb(est.total)} of memory ({est.describe()}), more than the "
        f"{_gb(limit)} of {source}. Lower {fields}, or set {MEMORY_LIMIT_ENV} to allow more.",
    )


def _path_of(part: str) -> str:
    """The config path a part is named after (``sensor[0]``), or ``num_envs``."""
    head = part.split(" ")[0]
    return head if head.startswith("sensor[") else "num_envs"
