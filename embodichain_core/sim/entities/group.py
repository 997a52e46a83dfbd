"""Rigid-object groups: K bodies per env managed together, tensors (N, K, ...)."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.sim.entities.base import Entity, StateSlices
from embodichain_core.sim.entities.rigid_object import RigidObject


class RigidObjectGroup(Entity):
    """Members are :class:`RigidObject` s named ``<uid>/<member>``."""

    kind = "rigid_object_group"
    state_only_reset = True

    def __init__(self, uid: str, cfg: Any, scene: Any, record: Any, parts: dict):
        super().__init__(uid, cfg, scene)
        self.member_names = [name for name, _ in record.extra["members"]]
        self.members = [
            RigidObject(m.uid, m, scene, body=m.uid, parts=parts.get(m.uid, {})) for _, m in record.extra["members"]
        ]

    @property
    def num_objects(self) -> int:
        return len(self.members)

    def find_bodies(self, names: Any, preserve_order: bool = False) -> tuple[list[int], list[str]]:
        from embodichain_core.sim.entities.base import find_names

        return find_names(self.member_names, names, preserve_order, "member", self.uid)

    def get_local_pose(self, to_matrix: bool = False) -> torch.Tensor:
        """(N, K, 7) or (N, K, 4, 4) member poses."""
        return torch.stack([m.get_local_pose(to_matrix) for m in self.members], dim=1)

    def set_local_pose(self, pose: torch.Tensor, env_ids: Any = None, obj_ids: Any = None) -> None:
        """Set (n, k, 7) poses of members ``obj_ids`` (all when None)."""
        ids = range(self.num_objects) if obj_ids is None else list(obj_ids)
        for k, obj in enumerate(ids):
            self.members[obj].set_local_pose(pose[:, k], env_ids)

    def get_velocity(self) -> torch.Tensor:
        return torch.stack([m.get_velocity() for m in self.members], dim=1)

    def clear_dynamics(self, env_ids: Any = None) -> None:
        for m in self.members:
            m.clear_dynamics(env_ids)

    def state_slices(self) -> StateSlices:
        return sum((m.state_slices() for m in self.members), StateSlices())

    def initial_state(self) -> list[np.ndarray]:
        return [a for m in self.members for a in m.initial_state()]

    def reset(self, env_ids: Any = None) -> None:
        for m in self.members:
            m.reset(env_ids)
