"""The per-env joint and link properties of an :class:`~embodichain_core.sim.entities.articulation.Articulation`
(a mixin): damping, armature, friction loss, drive gains and effort limits, joint limits, link
masses and friction. Setters follow the shape contract of
:mod:`~embodichain_core.sim.entities.model_fields` and write through ``sim.set_model_field``,
so each env keeps its own value.

Example:
    >>> robot.set_joint_drive(stiffness=[[100.0], [200.0]], joint_ids=[0])  # doctest: +SKIP
    >>> robot.get_qpos_limits().shape  # doctest: +SKIP
    torch.Size([2, 7, 2])
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from embodichain_core.sim.entities.model_fields import per_env_values

if TYPE_CHECKING:
    from embodichain_core.sim.scene import Scene

__all__ = ["JointModelFields"]


class JointModelFields:
    """Per-env joint and link model fields of an :class:`Articulation` (mixed in).

    The host class provides the attributes and helpers declared below (``Entity`` and
    ``Articulation`` set or define them).
    """

    uid: str
    scene: Scene
    dof_adr: torch.Tensor
    pos_act: torch.Tensor
    vel_act: torch.Tensor
    body_ids: torch.Tensor
    _joint_ids: list[int]
    cfg: Any
    num_envs: int
    joint_names: list[str]
    _shared_limits: np.ndarray | None  # jnt_range of every env until it is randomized per env

    if TYPE_CHECKING:  # defined by the host class (properties and methods of Entity/Articulation)

        @property
        def sim(self) -> Any: ...  # the SimBackend; Any as in Entity: its views (sim.qpos) are dynamic

        @property
        def num_links(self) -> int: ...

        @property
        def dof(self) -> int: ...

        def _ids(self, env_ids: Any) -> torch.Tensor: ...

        def _jids_np(self, joint_ids: Any) -> np.ndarray: ...

        def _out(self, t: torch.Tensor) -> torch.Tensor: ...

        def find_bodies(self, names: Any, preserve_order: bool = False) -> tuple[list[int], list[str]]: ...

    def _set_dof_field(self, field: str, values: Any, joint_ids: Any, env_ids: Any) -> None:
        env, jids = self._ids(env_ids), self._jids_np(joint_ids)
        vals = per_env_values(values, len(env), len(jids), f"{self.uid}: {field}")
        if len(env) and len(jids):
            self.sim.set_model_field(field, env.numpy(), self.dof_adr.numpy()[jids].tolist(), vals)
            self.sim.mark_dirty(env)

    def _get_dof_field(self, field: str, joint_ids: Any, env_ids: Any) -> torch.Tensor:
        env, jids = self._ids(env_ids), self._jids_np(joint_ids)
        vals = self.sim.model_field(field)[env.numpy()[:, None], self.dof_adr.numpy()[jids][None, :]]
        return self._out(torch.as_tensor(np.array(vals)))

    def set_joint_damping(self, damping: Any, joint_ids: Any = None, env_ids: Any = None) -> None:
        """Passive joint damping (N*m*s/rad or N*s/m), per env and joint (shape contract: module doc)."""
        self._set_dof_field("dof_damping", damping, joint_ids, env_ids)

    def get_joint_damping(self, joint_ids: Any = None, env_ids: Any = None) -> torch.Tensor:
        """(n, k) passive joint damping."""
        return self._get_dof_field("dof_damping", joint_ids, env_ids)

    def set_joint_armature(self, armature: Any, joint_ids: Any = None, env_ids: Any = None) -> None:
        """Joint armature (reflected rotor inertia, kg*m^2 or kg), per env and joint."""
        self._set_dof_field("dof_armature", armature, joint_ids, env_ids)

    def get_joint_armature(self, joint_ids: Any = None, env_ids: Any = None) -> torch.Tensor:
        """(n, k) joint armature."""
        return self._get_dof_field("dof_armature", joint_ids, env_ids)

    def set_joint_friction_loss(self, friction: Any, joint_ids: Any = None, env_ids: Any = None) -> None:
        """Dry joint friction (MuJoCo ``frictionloss``, N*m or N), per env and joint."""
        self._set_dof_field("dof_frictionloss", friction, joint_ids, env_ids)

    def get_joint_friction_loss(self, joint_ids: Any = None, env_ids: Any = None) -> torch.Tensor:
        """(n, k) dry joint friction."""
        return self._get_dof_field("dof_frictionloss", joint_ids, env_ids)

    def _write_drive(self, stiffness: Any, damping: Any, max_effort: Any, joint_ids: Any, env_ids: Any) -> None:
        """``set_joint_drive``'s writes: drive gains and effort limits of the driven joints."""
        env, jids = self._ids(env_ids).numpy(), self._jids_np(joint_ids)
        vals = {
            key: per_env_values(v, len(env), len(jids), f"{self.uid}: {key}")
            for key, v in (("stiffness", stiffness), ("damping", damping), ("max_effort", max_effort))
            if v is not None
        }
        if not len(env):
            return
        pos, vel = self.pos_act.numpy()[jids], self.vel_act.numpy()[jids]
        has, own_vel = pos >= 0, (pos >= 0) & (vel >= 0)
        servo_kv = has & (vel < 0)  # a kept position servo without a velocity servo: kv is its bias
        writes = []
        if "stiffness" in vals:
            writes += [
                ("actuator_gainprm", pos, has, 0, vals["stiffness"]),
                ("actuator_biasprm", pos, has, 1, -vals["stiffness"]),
            ]
        if "damping" in vals:
            writes += [
                ("actuator_gainprm", vel, own_vel, 0, vals["damping"]),
                ("actuator_biasprm", vel, own_vel, 2, -vals["damping"]),
                ("actuator_biasprm", pos, servo_kv, 2, -vals["damping"]),
            ]
        for field, acts, mask, col, values in writes:
            if mask.any():
                self.sim.set_model_field(field, env, (acts[mask].tolist(), col), values[:, mask])
        if "max_effort" in vals and has.any():
            eff = vals["max_effort"][:, has]
            jnt = np.asarray(self._joint_ids)[jids][has].tolist()
            self.sim.set_model_field("jnt_actfrcrange", env, jnt, np.stack((-eff, eff), -1))

    def get_joint_drive(self, joint_ids: Any = None, env_ids: Any = None) -> tuple[torch.Tensor, torch.Tensor]:
        """``(stiffness (n, k), damping (n, k))`` of the drives (0 where a joint has none)."""
        env, jids = self._ids(env_ids), self._jids_np(joint_ids)
        gain = self.sim.model_field("actuator_gainprm")[env.numpy()]
        out = np.zeros((2, len(env), len(jids)))
        for c, j in enumerate(jids):
            pa, va = int(self.pos_act[j]), int(self.vel_act[j])
            out[0, :, c] = gain[:, pa, 0] if pa >= 0 else 0.0
            if va >= 0:
                out[1, :, c] = gain[:, va, 0]
            elif pa >= 0:
                out[1, :, c] = -self.sim.model_field("actuator_biasprm")[env.numpy(), pa, 2]
        return self._out(torch.as_tensor(out[0])), self._out(torch.as_tensor(out[1]))

    def _link_geoms(self, link_names: Any) -> tuple[list[int], list[int]]:
        """(colliding geom ids, their column in the link list) of ``link_names`` (all when None)."""
        links = list(range(self.num_links)) if link_names is None else self.find_bodies(link_names)[0]
        model, geoms, cols = self.scene.model, [], []
        for col, link in enumerate(links):
            body = int(self.body_ids[link])
            for g in range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body]):
                if model.geom_contype[g] or model.geom_conaffinity[g]:
                    geoms.append(g)
                    cols.append(col)
        return geoms, cols

    def set_friction(self, friction: Any, link_names: Any = None, env_ids: Any = None) -> None:
        """Sliding friction of the colliding geoms of ``link_names``, per env and link."""
        env = self._ids(env_ids)
        links = self.num_links if link_names is None else len(self.find_bodies(link_names)[0])
        vals = per_env_values(friction, len(env), links, f"{self.uid}: geom friction")
        geoms, cols = self._link_geoms(link_names)
        if geoms and len(env):
            self.sim.set_model_field("geom_friction", env.numpy(), (geoms, 0), vals[:, cols])
            self.sim.mark_dirty(env)

    def get_friction(self, link_names: Any = None, env_ids: Any = None) -> torch.Tensor:
        """(n, k) sliding friction per link (its first colliding geom's; NaN for a link without one)."""
        env = self._ids(env_ids)
        links = self.num_links if link_names is None else len(self.find_bodies(link_names)[0])
        out = np.full((len(env), links), np.nan)
        field = self.sim.model_field("geom_friction")
        for g, col in reversed(list(zip(*self._link_geoms(link_names)))):
            out[:, col] = field[env.numpy(), g, 0]
        return self._out(torch.as_tensor(out))

    # -- limits ------------------------------------------------------------------------------------
    def get_qpos_limits(self) -> torch.Tensor:
        """(N, dof, 2) joint position limits (+-inf where unlimited)."""
        return self._out(torch.from_numpy(self.qpos_limits_array()))

    def qpos_limits_array(self, env_ids: Any = None, joint_ids: Any = None) -> np.ndarray:
        """(n, k, 2) float64 position limits of ``env_ids`` x ``joint_ids`` (+-inf where
        unlimited), as numpy: the cheap form for hot paths (a new array each call)."""
        cols = self._jids_np(joint_ids)
        n = self.num_envs if env_ids is None else len(self._ids(env_ids))
        if not self.sim.is_per_env("jnt_range"):
            if self._shared_limits is None:  # one value for every env, until randomized per env
                jnt = np.asarray(self._joint_ids)
                rng = np.array(self.scene.model.jnt_range[jnt])
                rng[~self.scene.model.jnt_limited[jnt].astype(bool)] = [-np.inf, np.inf]
                self._shared_limits = rng
            return np.repeat(self._shared_limits[None, cols], n, axis=0)
        jnt = np.asarray(self._joint_ids)[cols]
        rows = np.arange(self.num_envs) if env_ids is None else self._ids(env_ids).numpy()
        rng = np.array(self.sim.model_field("jnt_range")[rows[:, None], jnt[None, :]])
        rng[:, ~self.scene.model.jnt_limited[jnt].astype(bool)] = [-np.inf, np.inf]
        return rng

    def get_qvel_limits(self) -> torch.Tensor:
        """(N, dof) velocity limits from the drive config (``max_velocity``)."""
        from embodichain_core.sim.scene_build.drive_values import joint_value

        vals = [joint_value(self.cfg.drive_pros.max_velocity, j, "drive_pros.max_velocity") for j in self.joint_names]
        vals = [v if np.isfinite(v) else 1e10 for v in vals]
        return self._out(torch.as_tensor(vals).expand(self.num_envs, self.dof))

    def get_qf_limits(self) -> torch.Tensor:
        """(N, dof) effort limits (``max_effort``; 1e10 where unlimited)."""
        jnt = np.asarray(self._joint_ids)
        rng = np.array(self.sim.model_field("jnt_actfrcrange")[:, jnt, 1])
        rng[:, ~self.scene.model.jnt_actfrclimited[jnt].astype(bool)] = 1e10
        return self._out(torch.as_tensor(rng))

    # -- drives and masses -----------------------------------------------------------------------
    def set_joint_drive(
        self,
        stiffness: Any = None,
        damping: Any = None,
        max_effort: Any = None,
        joint_ids: Any = None,
        env_ids: Any = None,
    ) -> None:
        """Change per-env drive gains and effort limits of the driven joints among ``joint_ids``.

        Args:
            stiffness: drive ``kp`` (N*m/rad or N/m); None leaves it.
            damping: drive ``kv`` (N*m*s/rad or N*s/m); None leaves it.
            max_effort: symmetric actuator force limit (N*m or N); None leaves it.
            joint_ids: joints (all when None); joints without a drive are skipped.
            env_ids: envs (all when None).

        Each value follows the shape contract of :mod:`~embodichain_core.sim.entities.model_fields`
        (``n`` envs x ``k`` joints: a number, ``(k,)``, ``(n, k)``, ``(n, 1)`` or ``(n,)`` per env).
        """
        self._write_drive(stiffness, damping, max_effort, joint_ids, env_ids)

    def get_mass(self, link_names: Any = None) -> torch.Tensor:
        """(N, n_links) link masses."""
        ids = self.body_ids if link_names is None else self.body_ids[self.find_bodies(link_names)[0]]
        return self._out(torch.as_tensor(np.array(self.sim.model_field("body_mass")[:, ids.numpy()])))

    def set_mass(self, mass: Any, link_names: Any = None, env_ids: Any = None) -> None:
        """Set link masses (kg) per env and link (``(n, k)``, broadcast like
        :func:`~embodichain_core.sim.entities.model_fields.per_env_values`); inertias scale along."""
        env = self._ids(env_ids)
        ids = self.body_ids if link_names is None else self.body_ids[self.find_bodies(link_names)[0]]
        self.sim.set_body_masses(env, ids.numpy(), per_env_values(mass, len(env), len(ids), f"{self.uid}: mass"))
