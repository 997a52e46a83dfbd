"""Lights with per-env position, colour and intensity."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.base import Entity, as_array
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
        self._init_pos_np = self.init_pos.numpy().astype(np.float64)
        self._color0 = np.asarray(cfg.color, dtype=np.float64)
        self._touched = False
        # a world light that does not track: its *0 reference fields equal the written
        # values, so position/direction writes need no mj_setConst
        model = scene.model
        self._fixed_world = int(model.light_bodyid[self.light_id]) == 0 and int(model.light_mode[self.light_id]) == int(
            mujoco.mjtCamLight.mjCAMLIGHT_FIXED
        )

    def _ids_for_write(self, env_ids: Any) -> torch.Tensor:
        return self._ids(None) if self.is_global else self._ids(env_ids)

    def get_position(self) -> torch.Tensor:
        """(N, 3) light positions in the env frame."""
        return self._out(torch.as_tensor(np.array(self.sim.model_field("light_pos")[:, self.light_id])))

    def set_position(self, pos: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        self._touched = True
        vals = as_array(pos, len(ids), 3)
        self.sim.set_model_field("light_pos", ids, self.light_id, vals, set_const=not self._fixed_world)
        self.sim.set_model_field("light_pos0", ids, self.light_id, vals)
        self.sim.mark_dirty(ids)

    def get_color(self) -> torch.Tensor:
        return self._out(self._color)

    def set_color(self, color: Any, env_ids: Any = None) -> None:
        self.set_properties(env_ids, color=color)

    def get_intensity(self) -> torch.Tensor:
        return self._out(self._intensity)

    def set_intensity(self, intensity: Any, env_ids: Any = None) -> None:
        self.set_properties(env_ids, intensity=intensity)

    def get_direction(self) -> torch.Tensor:
        """(N, 3) unit directions (spot and sun/directional lights)."""
        return self._out(torch.as_tensor(np.array(self.sim.model_field("light_dir")[:, self.light_id])))

    def set_direction(self, direction: Any, env_ids: Any = None) -> None:
        ids = self._ids_for_write(env_ids)
        self._touched = True
        vals = as_array(direction, len(ids), 3)
        vals = vals / np.maximum(np.sqrt((vals * vals).sum(-1)), 1e-9)[:, None]
        self.sim.set_model_field("light_dir", ids, self.light_id, vals, set_const=not self._fixed_world)
        self.sim.set_model_field("light_dir0", ids, self.light_id, vals)
        self.sim.mark_dirty(ids)

    def set_properties(
        self,
        env_ids: Any = None,
        *,
        position: Any = None,
        color: Any = None,
        intensity: Any = None,
        direction: Any = None,
    ) -> None:
        """Set any of position, colour, intensity and direction of ``env_ids`` in one pass.

        The same as the single setters, with each model field written once (the
        randomization functors use it on every reset).

        Example:
            >>> light.set_properties(ids, color=torch.rand(len(ids), 3), intensity=torch.full((len(ids),), 20.0))
        """
        ids = self._ids_for_write(env_ids)
        if position is not None:
            self.set_position(position, ids)
        if direction is not None:
            self.set_direction(direction, ids)
        if color is None and intensity is None:
            return
        rows = ids.numpy()
        if color is not None:
            self._color.numpy()[rows] = as_array(color, len(rows), 3)
        if intensity is not None:
            self._intensity.numpy()[rows] = as_array(intensity, len(rows))
        self._write_diffuse(rows)

    def _write_diffuse(self, rows: np.ndarray) -> None:
        """Write MuJoCo's diffuse colour (colour x intensity / 30) and intensity of ``rows``."""
        self._touched = True
        intensity = self._intensity.numpy()[rows]
        scale = np.minimum(np.maximum(intensity / 30.0, 0.0), 1.0)[:, None]
        diffuse = np.minimum(np.maximum(self._color.numpy()[rows] * scale, 0.0), 1.0)
        self.sim.set_model_field("light_diffuse", rows, self.light_id, diffuse)
        self.sim.set_model_field("light_intensity", rows, self.light_id, intensity)
        mirrored = getattr(getattr(self.sim, "fields", None), "mirrored", None)
        if mirrored is not None:  # backend warp: MuJoCo Warp's renderer sees the intensity in the diffuse
            mirrored.add("light_intensity")

    def reset(self, env_ids: Any = None) -> None:
        """Restore the configured position, direction, colour and intensity (only if changed)."""
        if not self._touched:
            return
        ids = self._ids_for_write(env_ids)
        n = len(ids)
        direction = self.cfg.direction if self.cfg.light_type != "point" else None
        self.set_properties(
            ids,
            position=self._init_pos_np,
            direction=direction,
            color=np.broadcast_to(self._color0, (n, 3)),
            intensity=np.full(n, float(self.cfg.intensity)),
        )
        self._touched = self.is_global is False and n < self.num_envs
