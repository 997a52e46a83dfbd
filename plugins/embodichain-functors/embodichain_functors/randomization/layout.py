"""Layout randomization (class functors): objects on distinct grid cells, and a per-env
height shift of an anchor (a table) with everything standing on it."""

from __future__ import annotations

import warnings
from typing import Any, Optional, Sequence

import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.entities.robot import Robot

from embodichain_functors._common import ParamError, as_range, env_ids_of, randint, uniform
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._sim import read_model, step_envs, write_model

__all__ = ["planner_grid_cell_sampler", "randomize_anchor_height"]

_GROUPS = ("background", "rigid_object", "rigid_object_group", "articulation")


class planner_grid_cell_sampler(CheckedFunctor):
    """Place objects at the centres of distinct random cells of an xy grid, per env.

    Each env draws its own cells (no two objects share one). Objects keep their
    orientation; their z becomes ``reference_height``.

    Args (params):
        position_range: ``[[xmin, ymin], [xmax, ymax]]`` of the grid (env frame, metres).
        reference_height: z of the placed objects.
        object_uid_list: uids of the rigid objects to place.
        grid_size: ``[cols, rows]``; needs ``cols * rows >= len(object_uid_list)``.
        physics_update_step: physics steps to simulate these envs afterwards.

    Example:
        ``{"func": "planner_grid_cell_sampler", "mode": "reset", "params": {"position_range":
        [[0.3, -0.3], [0.7, 0.3]], "reference_height": 0.05, "object_uid_list": ["cube", "ball"],
        "grid_size": [4, 3]}}``
    """

    def check(
        self,
        env: Any,
        position_range: Any = None,
        reference_height: Any = None,
        object_uid_list: Any = (),
        grid_size: Any = (),
        **_: Any,
    ) -> None:
        name = type(self).__name__
        as_range(position_range, name, "position_range", 2)
        if isinstance(reference_height, bool) or not isinstance(reference_height, (int, float)):
            raise ParamError(name, "reference_height", f"must be a number, got {reference_height!r}")
        if (
            not isinstance(grid_size, (list, tuple))
            or len(grid_size) != 2
            or any(isinstance(g, bool) or not isinstance(g, int) or g < 1 for g in grid_size)
        ):
            raise ParamError(name, "grid_size", f"must be [cols, rows] of ints >= 1, got {grid_size!r}")
        for uid in object_uid_list:
            if not isinstance(env.scene.get(uid), RigidObject):
                raise ParamError(name, "object_uid_list", f"{uid!r} is not a rigid object of the scene")
        if len(object_uid_list) > grid_size[0] * grid_size[1]:
            raise ParamError(name, "grid_size", f"{grid_size} has fewer cells than {len(object_uid_list)} objects")

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        position_range: Sequence,
        reference_height: float,
        object_uid_list: Sequence[str],
        grid_size: Sequence[int],
        physics_update_step: int = -1,
    ) -> None:
        ids = env_ids_of(env, env_ids)
        low, high = as_range(position_range, type(self).__name__, "position_range", 2)
        cols, rows = int(grid_size[0]), int(grid_size[1])
        cells = torch.from_numpy(env.rng.random(ids, (cols * rows,)).argsort(axis=1))
        cell_size = (high - low) / torch.tensor([cols, rows], dtype=torch.float64)
        for k, uid in enumerate(object_uid_list):
            cell = cells[:, k]
            centre = low + (torch.stack((cell % cols, cell // cols), -1).to(torch.float64) + 0.5) * cell_size
            obj = env.scene[uid]
            pose = obj.get_local_pose()[ids].to(torch.float64)
            pose[:, :2], pose[:, 2] = centre, float(reference_height)
            obj.set_local_pose(pose, ids)
            obj.clear_dynamics(ids)
        step_envs(env, ids, physics_update_step)


class randomize_anchor_height(CheckedFunctor):
    """Shift an anchor (a table) to a random height per env, and everything on it along.

    The anchor moves to its configured z plus the draw; every other entity of
    ``include_groups`` (except ``exclude_uids`` and robots) moves by the same
    draw from its current z. x, y and orientations are unchanged. The draws are
    stored in ``env.<store_key>`` ((N,) float32).

    Args (params):
        anchor_uid: the anchor entity (background, rigid object, group or articulation).
        height_delta_range: ``[low, high]`` of the shift in metres, or
        height_delta_candidates: a list of shifts to pick from (one of the two).
        include_groups: scene groups moved along: ``background``, ``rigid_object``,
            ``rigid_object_group``, ``articulation``.
        exclude_uids: uids not moved.
        physics_update_step: physics steps to simulate these envs afterwards.
        store_key: env attribute receiving the draws.

    Example:
        ``{"func": "randomize_anchor_height", "mode": "reset", "params": {"anchor_uid": "table",
        "height_delta_range": [-0.05, 0.05]}}``
    """

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._fixed_shift = torch.zeros(env.num_envs, dtype=torch.float64)  # applied to fixed-base roots

    def check(
        self,
        env: Any,
        anchor_uid: Any = None,
        height_delta_range: Any = None,
        height_delta_candidates: Any = None,
        include_groups: Sequence[str] = _GROUPS,
        store_key: Any = "anchor_height_delta",
        **_: Any,
    ) -> None:
        name = type(self).__name__
        if env.scene.get(anchor_uid) is None:
            raise ParamError(name, "anchor_uid", f"no entity {anchor_uid!r} in the scene")
        if (height_delta_range is None) == (height_delta_candidates is None):
            raise ParamError(
                name, "height_delta_range", "give exactly one of height_delta_range and height_delta_candidates"
            )
        if height_delta_range is not None:
            as_range(height_delta_range, name, "height_delta_range")
        elif not isinstance(height_delta_candidates, (list, tuple)) or not height_delta_candidates:
            raise ParamError(name, "height_delta_candidates", "must be a non-empty list of numbers")
        bad = [g for g in include_groups if g not in _GROUPS]
        if bad:
            raise ParamError(name, "include_groups", f"unknown groups {bad}; choose from {list(_GROUPS)}")
        if not isinstance(store_key, str) or not store_key.isidentifier():
            raise ParamError(name, "store_key", f"must be an identifier, got {store_key!r}")
        if isinstance(env.scene.get(anchor_uid), RigidObjectGroup):
            warnings.warn(
                f"{name}: anchor {anchor_uid!r} is a group; its members are shifted relatively",
                RuntimeWarning,
                stacklevel=2,
            )

    def _draw(self, env: Any, ids: torch.Tensor, height_delta_range: Any, height_delta_candidates: Any) -> torch.Tensor:
        n = len(ids)
        if height_delta_range is not None:
            low, high = as_range(height_delta_range, type(self).__name__, "height_delta_range")
            return uniform(env, ids, low, high).reshape(n)
        values = torch.as_tensor(height_delta_candidates, dtype=torch.float64).reshape(-1)
        return values[randint(env, ids, len(values))]

    def _members(self, env: Any, anchor_uid: str, include_groups: Sequence[str], exclude_uids: Sequence[str]) -> list:
        scene, out = env.scene, []
        stores = {
            "background": scene.backgrounds,
            "rigid_object": scene.rigid_objects,
            "rigid_object_group": scene.groups,
            "articulation": scene.articulations,
        }
        for group in include_groups:
            out += [e for uid, e in stores[group].items() if uid != anchor_uid and uid not in exclude_uids]
        return out

    def _shift(self, env: Any, entity: Any, ids: torch.Tensor, dz: torch.Tensor, absolute: bool) -> None:
        if isinstance(entity, RigidObjectGroup):
            for member in entity.members:
                self._shift(env, member, ids, dz, False)
        elif isinstance(entity, RigidObject):
            pose = entity.get_local_pose()[ids].to(torch.float64)
            pose[:, 2] = (entity.init_pose[2] if absolute else pose[:, 2]) + dz
            entity.set_local_pose(pose, ids)
        elif isinstance(entity, Articulation) and not isinstance(entity, Robot):
            self._shift_articulation(env, entity, ids, dz, absolute)

    def _shift_articulation(
        self, env: Any, art: Articulation, ids: torch.Tensor, dz: torch.Tensor, absolute: bool
    ) -> None:
        if art.is_floating:
            pose = art.get_local_pose()[ids].to(torch.float64)
            pose[:, 2] = (float(art.init_root_pose[2]) if absolute else pose[:, 2]) + dz
            art.set_local_pose(pose, ids)
            return
        body = art.root_body_id
        pos = torch.as_tensor(read_model(env.sim, "body_pos", ids, body))
        base = float(art.scene.model.body_pos[body, 2]) if absolute else pos[:, 2] - self._fixed_shift[ids]
        pos[:, 2] = base + dz
        write_model(env.sim, ids, [("body_pos", body, pos)])

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        anchor_uid: str,
        height_delta_range: Optional[Sequence] = None,
        height_delta_candidates: Optional[Sequence[float]] = None,
        include_groups: Sequence[str] = _GROUPS,
        exclude_uids: Sequence[str] = (),
        physics_update_step: int = 0,
        store_key: str = "anchor_height_delta",
    ) -> None:
        ids = env_ids_of(env, env_ids)
        dz = self._draw(env, ids, height_delta_range, height_delta_candidates)
        self._shift(env, env.scene[anchor_uid], ids, dz, absolute=True)
        for entity in self._members(env, anchor_uid, include_groups, exclude_uids):
            self._shift(env, entity, ids, dz, absolute=False)
        self._fixed_shift[ids] = dz
        if getattr(env, store_key, None) is None:
            setattr(env, store_key, torch.zeros(env.num_envs))
        getattr(env, store_key)[ids] = dz.to(torch.float32)
        step_envs(env, ids, physics_update_step)
