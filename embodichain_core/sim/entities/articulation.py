"""Articulations: batched joint state, drives and link poses in EmbodiChain joint order.

Joint ids follow EmbodiChain's breadth-first link order (not MuJoCo's depth-first
qpos order); a name-to-address map makes ``get_qpos()[:, i]`` joint ``i``.
"""

from __future__ import annotations

from typing import Any, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.entities.base import Entity, StateSlices, as_array, as_values, find_names
from embodichain_core.sim.entities.joint_fields import JointModelFields
from embodichain_core.utils.math import pose_to_matrix


class Articulation(JointModelFields, Entity):
    """A jointed object; joint-indexed tensors are ``(N, dof)``.

    Per-env model fields (damping, armature, friction loss, drive gains, masses, geom
    friction) have setters/getters with one shape contract, see
    :mod:`embodichain_core.sim.entities.model_fields`.
    """

    kind = "articulation"
    state_only_reset = True

    def __init__(self, uid: str, cfg: Any, scene: Any, record: Any):
        super().__init__(uid, cfg, scene)
        model, p = scene.model, f"{uid}/"
        self.joint_names: list[str] = list(record.extra["joints"])
        self.link_names: list[str] = list(record.extra["bodies"])
        self._joint_ids = [self._name2id(mujoco.mjtObj.mjOBJ_JOINT, p + j) for j in self.joint_names]
        self.qpos_adr = torch.as_tensor([model.jnt_qposadr[j] for j in self._joint_ids], dtype=torch.long)
        self.dof_adr = torch.as_tensor([model.jnt_dofadr[j] for j in self._joint_ids], dtype=torch.long)
        self.body_ids = torch.as_tensor([self._name2id(mujoco.mjtObj.mjOBJ_BODY, p + b) for b in self.link_names])
        self.root_body_id = int(self.body_ids[0])
        self._init_mimic(record.extra.get("mimic", {}))
        self._init_drives(record.extra.get("driven", []), p, record.extra.get("drive_actuators"))
        self._init_root(model)
        self.default_qpos = self._default_qpos(model, getattr(record, "path", "") or uid)

    # -- construction helpers ----------------------------------------------------------------
    def _init_mimic(self, mimic: dict) -> None:
        names = self.joint_names
        self.mimic_ids = [names.index(j) for j in mimic]
        self.mimic_parents = [names.index(par) for par, _, _ in mimic.values()]
        self.mimic_multipliers = [k for _, k, _ in mimic.values()]
        self.mimic_offsets = [o for _, _, o in mimic.values()]
        adr = [int(self.scene.model.jnt_qposadr[j]) for j in self._joint_ids]
        self._mimic_child_adr = np.asarray([adr[i] for i in self.mimic_ids], dtype=np.int64)
        self._mimic_parent_adr = np.asarray([adr[i] for i in self.mimic_parents], dtype=np.int64)
        self._mimic_k = np.asarray(self.mimic_multipliers, dtype=np.float64)
        self._mimic_off = np.asarray(self.mimic_offsets, dtype=np.float64)
        self._mimic_chained = bool(set(self.mimic_ids) & set(self.mimic_parents))

    def _init_drives(self, driven: Sequence[str], prefix: str, actuators: dict | None = None) -> None:
        """Drive actuator ids per joint: the core's ``<joint>:pos``/``:vel``, or the model's
        own servos kept by ``keep_actuators`` (``actuators``: joint -> (pos name, vel name))."""
        model = self.scene.model
        pos = [-1] * self.dof
        vel = [-1] * self.dof
        for name in driven:
            i = self.joint_names.index(name)
            pos_name, vel_name = (actuators or {}).get(name, (f"{name}:pos", f"{name}:vel"))
            for ids, act in ((pos, pos_name), (vel, vel_name)):
                if act is not None:
                    ids[i] = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, prefix + act)
        self.driven_ids = torch.as_tensor([i for i in range(self.dof) if pos[i] >= 0], dtype=torch.long)
        self.pos_act = torch.as_tensor(pos, dtype=torch.long)
        self.vel_act = torch.as_tensor(vel, dtype=torch.long)
        self._pos_act_np = np.asarray(pos, dtype=np.int64)
        self._qpos_adr_np = self.qpos_adr.numpy().copy()
        self._dof_adr_np = self.dof_adr.numpy().copy()
        self._all_joints = np.arange(self.dof, dtype=np.int64)
        self._shared_limits: np.ndarray | None = None
        self._link_body: dict[str, int] = {}

    def _init_root(self, model: mujoco.MjModel) -> None:
        jnt = model.body_jntadr[self.root_body_id]
        self.is_floating = jnt >= 0 and model.jnt_type[jnt] == mujoco.mjtJoint.mjJNT_FREE
        self.root_qpos_adr = int(model.jnt_qposadr[jnt]) if self.is_floating else -1
        self.root_dof_adr = int(model.jnt_dofadr[jnt]) if self.is_floating else -1
        adr = self.root_qpos_adr
        #: (7,) float64 initial root pose of a floating base (xyz + wxyz; empty when fixed)
        self.init_root_pose = torch.as_tensor(np.array(model.qpos0[adr : adr + 7] if self.is_floating else []))

    def _default_qpos(self, model: mujoco.MjModel, path: str) -> torch.Tensor:
        """``init_qpos`` (one value per joint, checked here: the joint count is known only
        after compile), else the model's ``qpos0``."""
        init = getattr(self.cfg, "init_qpos", None)
        if init is None:
            return torch.as_tensor(model.qpos0[self.qpos_adr.numpy()], dtype=torch.float64)
        init = torch.as_tensor(np.asarray(init, dtype=np.float64))
        if init.shape != (self.dof,):
            raise ConfigError(
                f"{path}.init_qpos",
                f"{self.uid!r} has {self.dof} joints (in this order: {self.joint_names}); got {init.numel()} values",
            )
        return init

    # -- sizes and names --------------------------------------------------------------------------
    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def num_links(self) -> int:
        return len(self.link_names)

    @property
    def root_link_name(self) -> str:
        return self.link_names[0]

    def find_joints(self, names: Any, preserve_order: bool = False) -> tuple[list[int], list[str]]:
        """Joint ids and names matching regexes ``names`` (full match)."""
        return find_names(self.joint_names, names, preserve_order, "joint", self.uid)

    def find_bodies(self, names: Any, preserve_order: bool = False) -> tuple[list[int], list[str]]:
        """Link ids and names matching regexes ``names``."""
        return find_names(self.link_names, names, preserve_order, "link", self.uid)

    def _jids_np(self, joint_ids: Any) -> np.ndarray:
        if joint_ids is None or (isinstance(joint_ids, slice) and joint_ids == slice(None)):
            return self._all_joints
        if isinstance(joint_ids, torch.Tensor):
            return joint_ids.detach().cpu().numpy().astype(np.int64).reshape(-1)
        return np.asarray(joint_ids, dtype=np.int64).reshape(-1)

    def _jids(self, joint_ids: Any) -> torch.Tensor:
        return torch.from_numpy(self._jids_np(joint_ids).copy())

    # -- joint state ------------------------------------------------------------------------------
    def _sim_index(self, name: str) -> torch.Tensor:
        """A constant index of this entity on the sim's device, copied there once:
        ``qpos``/``dof`` (the joints' addresses), ``pos``/``vel`` + ``_cols``/``_acts``
        (the joints with a position/velocity drive, and those actuators)."""
        cache = self.__dict__.setdefault("_sim_indices", {})
        out = cache.get(name)
        if out is None:
            kind, part = name.split("_", 1) if "_" in name else (name, "adr")
            if part == "adr":
                host = getattr(self, f"{kind}_adr")
            else:
                act = self.pos_act if kind == "pos" else self.vel_act
                host = torch.nonzero(act >= 0).flatten() if part == "cols" else act[act >= 0]
            out = cache[name] = host.to(self.sim.device, copy=True)
        return out

    def get_qpos(self, target: bool = False) -> torch.Tensor:
        """(N, dof) joint positions, or the drive targets with ``target=True``."""
        sim = self.sim
        out = sim.qpos[:, self._sim_index("qpos")]
        if target:
            out = out.clone()
            out[:, self._sim_index("pos_cols")] = sim.ctrl[:, self._sim_index("pos_acts")]
        return self._out(out)

    def set_qpos(self, qpos: Any, joint_ids: Any = None, env_ids: Any = None, target: bool = True) -> None:
        """Set drive targets (``target=True``) or teleport the joints (``target=False``).

        Teleporting also sets the drive targets, and mimic joints follow their parents.
        """
        ids, cols = self._ids(env_ids), self._jids_np(joint_ids)
        values = as_array(qpos, len(ids), len(cols))
        rows = ids.numpy()[:, None]
        acts = self._pos_act_np[cols]
        driven = acts >= 0
        route = self.state_route
        if driven.all():
            route.write("ctrl", (rows, acts[None, :]), values)
        elif driven.any():
            route.write("ctrl", (rows, acts[driven][None, :]), values[:, driven])
        if not target:
            route.write("qpos", (rows, self._qpos_adr_np[cols][None, :]), values)
            self._apply_mimic(rows)
            self.sim.mark_dirty(ids)

    def _apply_mimic(self, rows: np.ndarray) -> None:
        """Mimic joints of ``rows`` ((n, 1) env indices) follow their parents."""
        route = self.state_route
        if self._mimic_chained:  # a mimic of a mimic: in order
            for child, parent, k, off in zip(
                self._mimic_child_adr, self._mimic_parent_adr, self._mimic_k, self._mimic_off
            ):
                route.write("qpos", (rows[:, 0], child), k * route.read("qpos", (rows[:, 0], parent)) + off)
        elif self._mimic_child_adr.size:
            parents = route.read("qpos", (rows, self._mimic_parent_adr))
            route.write("qpos", (rows, self._mimic_child_adr), parents * self._mimic_k + self._mimic_off)

    def qpos_array(self, env_ids: Any = None, joint_ids: Any = None) -> np.ndarray:
        """(n, k) joint positions of ``env_ids`` x ``joint_ids`` as numpy, in the simulation's
        dtype (float64 on ``mujoco_batch``): the cheap form for hot paths (a new array each call)."""
        rows = self._ids(env_ids).numpy()[:, None]
        return np.array(self.state_route.read("qpos", (rows, self._qpos_adr_np[self._jids_np(joint_ids)][None, :])))

    def get_qvel(self, target: bool = False) -> torch.Tensor:
        """(N, dof) joint velocities, or velocity targets with ``target=True``."""
        sim = self.sim
        if target:
            out = torch.zeros(self.num_envs, self.dof, dtype=sim.dtype, device=sim.device)
            out[:, self._sim_index("vel_cols")] = sim.ctrl[:, self._sim_index("vel_acts")]
            return self._out(out)
        return self._out(sim.qvel[:, self._sim_index("dof")])

    def set_qvel(self, qvel: Any, joint_ids: Any = None, env_ids: Any = None, target: bool = True) -> None:
        """Set velocity targets of the drives, or the joint velocities (``target=False``)."""
        ids, jids = self._ids(env_ids), self._jids(joint_ids)
        values = as_values(qvel, len(ids), len(jids))
        if target:
            acts = self.vel_act[jids]
            driven = acts >= 0
            self.state_route.write("ctrl", (ids[:, None], acts[driven][None, :]), values[:, driven])
        else:
            self.state_route.write("qvel", (ids[:, None], self.dof_adr[jids][None, :]), values)
            self.sim.mark_dirty(ids)

    def get_qf(self) -> torch.Tensor:
        """(N, dof) joint efforts: drive forces plus applied forces."""
        dof = self._sim_index("dof")
        return self._out(self.sim.qfrc_actuator[:, dof] + self.sim.qfrc_applied[:, dof])

    def set_qf(self, qf: Any, joint_ids: Any = None, env_ids: Any = None) -> None:
        """Apply joint efforts (held until changed) through ``qfrc_applied``."""
        ids, jids = self._ids(env_ids), self._jids(joint_ids)
        values = as_values(qf, len(ids), len(jids))
        self.state_route.write("qfrc_applied", (ids[:, None], self.dof_adr[jids][None, :]), values)

    # -- links and root -------------------------------------------------------------------------------
    def get_link_pose(self, link_name: str, env_ids: Any = None, to_matrix: bool = False) -> torch.Tensor:
        """Pose of one link in the env frame, (n, 7) or (n, 4, 4)."""
        body = self._link_body.get(link_name) if isinstance(link_name, str) else None
        if body is None:  # resolve a name (regex) once
            body = int(self.body_ids[self.find_bodies(link_name)[0][0]])
            if isinstance(link_name, str):
                self._link_body[link_name] = body
        rows = slice(None) if env_ids is None else self._ids(env_ids)
        pose = self.state_route.pose("xpos", "xquat", (rows, body))
        return pose_to_matrix(pose) if to_matrix else pose

    def get_local_pose(self, to_matrix: bool = False) -> torch.Tensor:
        """Root link pose, (N, 7) or (N, 4, 4)."""
        if self.is_floating:
            pose = self.state_route.rows("qpos", (slice(None), slice(self.root_qpos_adr, self.root_qpos_adr + 7)))
        else:
            pose = self.state_route.pose("xpos", "xquat", (slice(None), self.root_body_id))
        return pose_to_matrix(pose) if to_matrix else pose

    def set_local_pose(self, pose: Any, env_ids: Any = None) -> None:
        """Move the root of a floating-base articulation (fixed bases cannot move)."""
        if not self.is_floating:
            raise ValueError(f"{self.uid}: the base is fixed (fix_base=True); its root pose cannot be set")
        from embodichain_core.utils.math import as_pose7

        ids = self._ids(env_ids)
        pose7 = as_values(as_pose7(torch.as_tensor(pose, dtype=torch.float64)), len(ids), 7)
        self.state_route.write("qpos", (ids, self._root_cols()), pose7)
        self.sim.mark_dirty(ids)

    def _root_cols(self) -> slice:
        """The qpos columns of a floating root (position, then wxyz quaternion)."""
        return slice(self.root_qpos_adr, self.root_qpos_adr + 7)

    # -- dynamics -------------------------------------------------------------------------------------
    def clear_dynamics(self, env_ids: Any = None) -> None:
        """Zero joint velocities and applied efforts of ``env_ids``."""
        rows, route = self._ids(env_ids).numpy(), self.state_route
        route.write("qvel", (rows[:, None], self._dof_adr_np), 0.0)
        route.write("qfrc_applied", (rows[:, None], self._dof_adr_np), 0.0)
        if self.is_floating:
            route.write("qvel", (rows, slice(self.root_dof_adr, self.root_dof_adr + 6)), 0.0)
        self.sim.mark_dirty(rows)

    # -- reset ---------------------------------------------------------------------------------------
    def state_slices(self) -> StateSlices:
        qpos, qvel = self.qpos_adr.tolist(), self.dof_adr.tolist()
        if self.is_floating:
            qpos += range(self.root_qpos_adr, self.root_qpos_adr + 7)
            qvel += range(self.root_dof_adr, self.root_dof_adr + 6)
        ctrl = [int(a) for a in torch.cat((self.pos_act, self.vel_act)) if a >= 0]
        return StateSlices(qpos=qpos, qvel=qvel, ctrl=ctrl)

    def initial_state(self) -> list[np.ndarray]:
        return [self.default_qpos.detach().cpu().numpy(), self.init_root_pose.numpy()]

    def reset(self, env_ids: Any = None) -> None:
        """Joints (and their drive targets) to ``default_qpos``, a floating root to
        ``init_root_pose``, at rest: zero velocities, velocity targets and applied efforts."""
        ids = self._ids(env_ids)
        if self.is_floating:
            self.state_route.write("qpos", (ids, self._root_cols()), self.init_root_pose)
        self.set_qpos(self.default_qpos.expand(len(ids), self.dof), env_ids=ids, target=False)
        mask = self.vel_act >= 0
        if mask.any():
            self.state_route.write("ctrl", (ids[:, None], self.vel_act[mask][None, :]), 0.0)
        self.clear_dynamics(ids)
