"""Cached physics observations (class functors): an object's physical attributes and an
articulation's joint drives. Values are read once and cached; ``reset(env_ids)``
(called by the manager on every env reset) drops the cache, so randomized values
show up in the next episode. Every call returns clones."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.rigid_object import RigidObject

from embodichain_functors._common import ParamError
from embodichain_functors._functor import CheckedFunctor

__all__ = ["get_rigid_object_physics_attributes", "get_articulation_joint_drive"]


def _t(values: Any) -> torch.Tensor:
    return torch.as_tensor(np.array(values), dtype=torch.float32)


class _CachedObservation(CheckedFunctor):
    """Caches ``self.compute(env, uid)`` per uid until :meth:`reset`."""

    kinds: tuple = ()

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._cache: dict[str, dict[str, torch.Tensor]] = {}

    def check(self, env: Any, entity_cfg: Any = None) -> None:
        uid = getattr(entity_cfg, "uid", None)
        if not isinstance(env.scene.get(uid), self.kinds):
            kinds = " or ".join(k.__name__ for k in self.kinds)
            raise ParamError(type(self).__name__, "entity_cfg", f"{uid!r} is not a {kinds}")

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        """Drop the cache (values are recomputed for every env on the next call)."""
        self._cache.clear()

    def compute(self, env: Any, entity: Any) -> dict[str, torch.Tensor]:
        raise NotImplementedError

    def __call__(self, env: Any, obs: Any, entity_cfg: Any) -> dict[str, torch.Tensor]:
        uid = entity_cfg.uid
        if uid not in self._cache:
            self._cache[uid] = self.compute(env, env.scene[uid])
        return {k: v.clone() for k, v in self._cache[uid].items()}


class get_rigid_object_physics_attributes(_CachedObservation):
    """A rigid object's ``{mass (N,), friction (N,), damping (N, 6), inertia (N, 3)}``.

    ``damping`` is the free joint's linear and angular damping (zeros for
    kinematic objects); ``inertia`` the principal moments; ``friction`` the
    sliding friction of the first collision geom.

    Args (params):
        entity_cfg: the rigid object.

    Example:
        ``{"func": "get_rigid_object_physics_attributes", "mode": "add", "name": "object/cube_physics",
        "params": {"entity_cfg": {"uid": "cube"}}}``
    """

    kinds = (RigidObject,)

    def compute(self, env: Any, obj: RigidObject) -> dict[str, torch.Tensor]:
        sim, n = env.sim, env.num_envs
        damping = torch.zeros(n, 6)
        if obj.is_dynamic:
            damping = _t(sim.model_field("dof_damping")[:, obj.dof_adr : obj.dof_adr + 6])
        return {
            "mass": obj.get_mass(),
            "friction": obj.get_friction(),
            "damping": damping,
            "inertia": _t(sim.model_field("body_inertia")[:, obj.body_id]),
        }


class get_articulation_joint_drive(_CachedObservation):
    """An articulation's joint drives: stiffness, damping, effort and velocity limits, friction, armature.

    Each value is (N, dof): ``stiffness``, ``damping``, ``max_effort``,
    ``max_velocity``, ``friction`` (frictionloss), ``armature``.

    Undriven joints report zero stiffness and damping.

    Args (params):
        entity_cfg: the articulation or robot.

    Example:
        ``{"func": "get_articulation_joint_drive", "mode": "add", "name": "robot/drive",
        "params": {"entity_cfg": {"uid": "robot"}}}``
    """

    kinds = (Articulation,)

    def compute(self, env: Any, art: Articulation) -> dict[str, torch.Tensor]:
        sim, n = env.sim, env.num_envs
        gain = np.array(sim.model_field("actuator_gainprm")[..., 0])
        stiffness, damping = torch.zeros(n, art.dof), torch.zeros(n, art.dof)
        driven = (art.pos_act >= 0).nonzero().flatten()
        if len(driven):
            stiffness[:, driven] = _t(gain[:, art.pos_act[driven].numpy()])
            damping[:, driven] = _t(gain[:, art.vel_act[driven].numpy()])
        dofs = art.dof_adr.numpy()
        return {
            "stiffness": stiffness,
            "damping": damping,
            "max_effort": art.get_qf_limits(),
            "max_velocity": art.get_qvel_limits(),
            "friction": _t(sim.model_field("dof_frictionloss")[:, dofs]),
            "armature": _t(sim.model_field("dof_armature")[:, dofs]),
        }
