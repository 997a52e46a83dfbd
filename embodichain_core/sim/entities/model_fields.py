"""Per-env model fields of articulations and the scene: the values users randomize.

Every setter writes through the simulation interface (``sim.set_model_field``), so each
env keeps its own value; a field first written per env stops being shared.

**Shape contract** of every per-joint (per-link) setter, for ``n`` envs (``env_ids``) and
``k`` joints (``joint_ids``) or links (``link_names``), numpy broadcasting to ``(n, k)``:

* a number: every env and joint;
* ``(k,)``: one value per joint, the same in every env;
* ``(n, k)``: per env and joint; ``(n, 1)``: per env, the same for every joint;
* ``(n,)`` when it cannot be per joint (``n != k``, or ``k == 1``): per env.

Anything else is a ``ValueError`` naming the expected shapes. Getters return
``(n, k)`` float32 tensors. Gravity (:func:`set_gravity`) is ``(3,)`` or ``(n, 3)``.

Example:
    >>> robot.set_joint_damping(torch.linspace(0.5, 5.0, 4)[:, None], joint_ids=[0, 1])  # doctest: +SKIP
    >>> robot.get_joint_damping(joint_ids=[0, 1])[:, 0]  # doctest: +SKIP
    tensor([0.5000, 2.0000, 3.5000, 5.0000])
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from embodichain_core.sim.entities.base import env_index

if TYPE_CHECKING:
    from embodichain_core.sim.scene import Scene

_GRAVITY = "opt.gravity"


def per_env_values(values: Any, n: int, k: int, what: str = "values") -> np.ndarray:
    """``values`` as a float64 ``(n, k)`` array following the shape contract (module doc).

    Raises:
        ValueError: a shape that does not broadcast, naming ``what`` and the valid shapes.
    """
    if isinstance(values, torch.Tensor):
        values = values.detach().cpu().numpy()
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == n and (n != k or k == 1):
        arr = arr[:, None]
    try:
        return np.broadcast_to(arr, (n, k))
    except ValueError:
        raise ValueError(
            f"{what}: got shape {arr.shape}; expected a number, ({k},) per joint/link, "
            f"({n}, {k}) per env and joint/link, ({n}, 1) or ({n},) per env"
        ) from None


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

    if TYPE_CHECKING:  # defined by the host class (properties and methods of Entity/Articulation)

        @property
        def sim(self) -> Any: ...  # the SimBackend; Any as in Entity: its views (sim.qpos) are dynamic

        @property
        def num_links(self) -> int: ...

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


def set_gravity(sim: Any, gravity: Any, env_ids: Any = None) -> None:
    """Gravity per env: ``(3,)`` for every env in ``env_ids``, or ``(n, 3)``.

    Raises:
        ValueError: a bad shape, or a backend where gravity is one global option.
    """
    env = env_index(env_ids, sim.num_envs).numpy()
    vals = np.asarray(gravity.detach().cpu().numpy() if isinstance(gravity, torch.Tensor) else gravity, dtype=float)
    try:
        vals = np.broadcast_to(vals, (len(env), 3))
    except ValueError:
        raise ValueError(f"gravity: got shape {vals.shape}; expected (3,) or ({len(env)}, 3)") from None
    if not len(env):
        return
    try:
        sim.set_model_field(_GRAVITY, env, Ellipsis, vals)
    except (AttributeError, KeyError, ValueError) as err:
        raise ValueError(
            f"gravity is a global option on this simulation backend (per-env gravity is "
            f"unavailable here: {err}); set physics_config.gravity in the config instead"
        ) from err
    sim.mark_dirty(env)


def get_gravity(sim: Any, env_ids: Any = None) -> torch.Tensor:
    """(n, 3) gravity of ``env_ids``."""
    env = env_index(env_ids, sim.num_envs).numpy()
    if sim.is_per_env(_GRAVITY):
        try:
            return torch.as_tensor(np.array(sim.model_field(_GRAVITY)[env]), dtype=torch.float32)
        except (AttributeError, KeyError) as err:
            raise ValueError(f"gravity is a global option on this simulation backend: {err}") from err
    return torch.as_tensor(np.array(sim.model.opt.gravity), dtype=torch.float32).expand(len(env), 3).clone()
