"""Where an articulation's MjSpec comes from: inline MJCF or a URDF/MJCF file."""

from __future__ import annotations

from typing import Any

import mujoco

from embodichain_core.config.errors import ConfigError


def spec_from_cfg(cfg: Any) -> mujoco.MjSpec:
    """Load ``cfg.mjcf`` (an XML string) or ``cfg.fpath`` (URDF/MJCF via ``get_data_path``)."""
    if getattr(cfg, "mjcf", None):
        try:
            return mujoco.MjSpec.from_string(cfg.mjcf)
        except Exception as err:
            raise ConfigError("mjcf", f"invalid MJCF for {cfg.uid!r}: {err}") from err
    if not getattr(cfg, "fpath", None):
        raise ConfigError("fpath", f"{type(cfg).__name__} {cfg.uid!r} needs 'fpath' (URDF/MJCF) or 'mjcf'")
    from embodichain_core.sim.scene_build.articulation_loader import load_articulation_spec
    from embodichain_core.sim.data import get_data_path

    return load_articulation_spec(get_data_path(cfg.fpath))
