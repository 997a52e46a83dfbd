"""Visual randomization: lights, materials (colours, textures), cameras.

``filter_visual_rand=True`` removes the ``randomize_*`` functors of this module
(category ``randomization.visual``); the deterministic ``set_*`` ones stay.
Materials live in :mod:`.materials`, cameras in :mod:`.cameras`; both are
re-exported here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.light import Light

from embodichain_functors._common import as_range, check_optional_range, entity_of, env_ids_of, uniform_np, validated
from embodichain_functors.randomization.cameras import randomize_camera_extrinsics, randomize_camera_intrinsics
from embodichain_functors.randomization.materials import (
    randomize_visual_material,
    set_rigid_object_group_visual_material,
    set_rigid_object_visual_material,
)

VISUAL = "randomization.visual"

__all__ = [
    "randomize_light",
    "randomize_visual_material",
    "set_rigid_object_visual_material",
    "set_rigid_object_group_visual_material",
    "randomize_camera_extrinsics",
    "randomize_camera_intrinsics",
]


def _check_light(
    env: Any,
    entity_cfg: SceneEntityCfg,
    position_range: Any = None,
    color_range: Any = None,
    intensity_range: Any = None,
    direction_range: Any = None,
) -> None:
    name = "randomize_light"
    entity_of(env, entity_cfg, name, (Light,))
    check_optional_range(position_range, name, "position_range", 3)
    check_optional_range(color_range, name, "color_range", 3)
    check_optional_range(intensity_range, name, "intensity_range")
    check_optional_range(direction_range, name, "direction_range", 3)


_LIGHT_PARAMS = {
    "pos": ("position_range", 3),
    "color": ("color_range", 3),
    "intensity": ("intensity_range", None),
    "dir": ("direction_range", 3),
}


def _light_draws(env: Any, light: Light, ids: Any, ranges: dict) -> dict[str, np.ndarray]:
    """One draw per env (one shared draw for a global light, from the first env's stream)
    of each given range."""
    n = len(ids)
    rows = ids[:1] if light.is_global else ids
    out = {}
    for key, rng in ranges.items():
        if rng is not None:
            param, width = _LIGHT_PARAMS[key]
            low, high = as_range(rng, "randomize_light", param, width)
            draw = uniform_np(env, rows, low, high)
            out[key] = np.broadcast_to(draw, (n,) + draw.shape[1:]) if light.is_global else draw
    return out


@validated(_check_light)
def randomize_light(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    position_range: Any = None,
    color_range: Any = None,
    intensity_range: Any = None,
    direction_range: Any = None,
) -> None:
    """Randomize a light's position, colour, intensity and direction per env.

    Point and spot lights draw per env; sun/directional lights are global (as the
    core's ``Light`` treats them): one draw is applied to every env.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the light.
        position_range: ``[[x, y, z] low, [...] high]`` added to the configured position
            (ignored for sun/directional lights).
        color_range: ``[[r, g, b] low, [...] high]`` absolute colour in [0, 1].
        intensity_range: ``[low, high]`` added to the configured intensity (clamped at 0).
        direction_range: ``[[x, y, z] low, [...] high]`` added to the configured direction
            (only for sun/directional and spot lights).

    Example:
        ``{"func": "randomize_light", "mode": "interval", "interval_step": 5, "params": {"entity_cfg":
        {"uid": "point"}, "position_range": [[-0.5, -0.5, 0], [0.5, 0.5, 0]],
        "color_range": [[0.6, 0.6, 0.6], [1, 1, 1]], "intensity_range": [-10.0, 10.0]}}``
    """
    light: Light = env.scene[entity_cfg.uid]
    ids = torch.arange(env.num_envs) if light.is_global else env_ids_of(env, env_ids)
    cfg = light.cfg
    point_like = not light.is_global
    draws = _light_draws(
        env,
        light,
        ids,
        {
            "pos": position_range if point_like else None,
            "color": color_range,
            "intensity": intensity_range,
            "dir": direction_range if cfg.light_type != "point" else None,
        },
    )
    pos = light.init_pos.numpy() + draws["pos"] if "pos" in draws else None
    direction = np.asarray(cfg.direction, dtype=np.float64) + draws["dir"] if "dir" in draws else None
    color = np.minimum(np.maximum(draws["color"], 0.0), 1.0) if "color" in draws else None
    intensity = np.maximum(draws["intensity"] + float(cfg.intensity), 0.0) if "intensity" in draws else None
    light.set_properties(ids, position=pos, color=color, intensity=intensity, direction=direction)


randomize_light.embodichain_category = VISUAL  # type: ignore[attr-defined]
