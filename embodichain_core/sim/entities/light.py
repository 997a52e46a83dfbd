"""Lights with per-env position, colour and intensity."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.base import Entity, as_values
from embodichain_core.utils.math import init_pos_from_cfg


class Light(Entity):
    """A scene light. Point and spot lights differ per env; ``sun``/``direction``
    lights are global (one value broadcast to every env)."""

    kind = "light"

    def __init__(self, uid: str, cfg: Any, scene: Any):
        super().__init__(uid, cfg, scene)
        self.light_id = self._name2id(mujoco.mjtObj.mjOBJ_LIGHT, uid)
        self.is_global = cfg.light_type in ("sun", "direction", "directional")
        n = self.num_envs
        self._color = torch.as_tensor(cfg.color, dtype=torch.float64).expand(n, 3).clone()
        self._intensity = torch.full((n,), float(cfg.intensity), dtype=torch.float64)
        self.init_pos = torch.as_tensor(init_pos_from_cfg(cfg.init_pos, cfg.init_local_pose))
        self._touched = False

    def _ids_for_write(self, env_ids: Any) -> torch.Tensor:
        return self._ids(None) if self.is_global else self._ids(env_ids)

    def get_position(self) -> torch.Tensor:
        """(N, 3) light positions in the env frame."""
        return self._out(torch.as_tensor(np.array(self.sim.model_field("light_pos")[:, self.light_id])))

    def set_position(self, pos: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        self._touched = True
        vals = as_values(pos, len(ids), 3)
        self.sim.set_model_field("light_pos", ids, self.light_id, vals.numpy())
        self.sim.set_model_field("light_pos0", ids, self.light_id, vals.numpy())
        self.sim.mark_dirty(ids)

    def get_color(self) -> torch.Tensor:
        return self._out(self._color)

    def set_color(self, color: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        self._color[ids] = as_values(color, len(ids), 3)
        self._write_diffuse(ids)

    def get_intensity(self) -> torch.Tensor:
        return self._out(self._intensity)

    def set_intensity(self, intensity: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        self._intensity[ids] = as_values(intensity, len(ids))
        self._write_diffuse(ids)

    def set_direction(self, direction: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        vals = as_values(direction, len(ids), 3)
        vals = vals / vals.norm(dim=-1, keepdim=True).clamp_min(1e-9)
        self.sim.set_model_field("light_dir", ids, self.light_id, vals.numpy())
        self.sim.set_model_field("light_dir0", ids, self.light_id, vals.numpy())

    def _write_diffuse(self, ids: torch.Tensor) -> None:
        self._touched = True
        scale = (self._intensity[ids] / 30.0).clamp(0.0, 1.0)[:, None]
        diffuse = (self._color[ids] * scale).clamp(0.0, 1.0).numpy()
        self.sim.set_model_field("light_diffuse", ids, self.light_id, diffuse)
        self.sim.set_model_field("light_intensity", ids, self.light_id, self._intensity[ids].numpy())

    def reset(self, env_ids: Any = None) -> None:
        """Restore the configured position, colour and intensity (only if changed)."""
        if not self._touched:
            return
        ids = self._ids_for_write(env_ids)
        self.set_position(self.init_pos.expand(len(ids), 3), ids)
        self._color[ids] = torch.as_tensor(self.cfg.color, dtype=torch.float64)
        self._intensity[ids] = float(self.cfg.intensity)
        self._write_diffuse(ids)
        self._touched = self.is_global is False and len(ids) < self.num_envs
