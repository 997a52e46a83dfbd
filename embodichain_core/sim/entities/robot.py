"""Robots: articulations with control parts, proprioception and kinematics.

Kinematics of a control part go through ``robot.solvers[part]``, built by the
robot config's optional ``build_solvers(robot) -> {part: solver}`` hook (robot
plugins provide them, e.g. embodichain-robots), or else from the config's
``solver_cfg`` (``{part: {"class_type": name, ...}}``) with the solver classes
plugins register (:mod:`embodichain_core.sim.entities.solvers`). A solver offers:

* ``joint_ids``: the robot joint ids it solves for (the part's joints, in order);
* ``root_link_name``: the link its poses are expressed in;
* ``get_fk(qpos (n, k)) -> (n, 4, 4)``: the part TCP in the root link frame;
* ``get_ik(target (n, 4, 4), qpos_seed (n, k)) -> (success (n,), qpos (n, k))``;
* optionally ``fk_on_device = True``: ``get_fk`` computes on its input's device and depends
  on nothing but ``qpos``, ``chain`` and ``tcp``; part FK then runs on the sim's device
  (no host copy), and on the CPU the current pose is reused while those inputs are equal;
* optionally ``ik_on_device = True`` and ``get_ik_on_device(target, qpos_seed)``: on the
  device route IK then starts on the sim's device (:mod:`~embodichain_core.sim.entities.part_ik`).

:meth:`Robot.compute_fk` (with ``name``) and :meth:`Robot.compute_ik` convert
between the env frame and the root link frame.
"""

from __future__ import annotations

from typing import Any, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.part_ik import ik_route, solve_part_ik
from embodichain_core.config.joint_check import match_part_patterns
from embodichain_core.utils.math import matrix_to_pose, pose_to_matrix, transform_inverse
from embodichain_core.utils.suggest import did_you_mean


class Robot(Articulation):
    """The env's agent. ``control_parts`` map part names to joint ids.

    Example:
        >>> robot.get_joint_ids("left_arm")
        [6, 8, 10, 12, 14, 16, 18]
    """

    kind = "robot"

    def __init__(self, uid: str, cfg: Any, scene: Any, record: Any):
        super().__init__(uid, cfg, scene, record)
        self.control_parts: dict[str, list[int]] = {}
        path = getattr(record, "path", "") or "robot"
        for part, patterns in (cfg.control_parts or {}).items():
            self.control_parts[part] = match_part_patterns(self.joint_names, path, str(part), patterns)
        self.solvers: dict[str, Any] = {}
        builder = getattr(cfg, "build_solvers", None)
        if callable(builder):
            self.solvers = builder(self) or {}
        elif getattr(cfg, "solver_cfg", None):
            from embodichain_core.sim.entities.solvers import build_cfg_solvers

            path = getattr(record, "path", "") or uid
            self.solvers = build_cfg_solvers(self, cfg.solver_cfg, f"{path}.solver_cfg")
        self._index_cache: dict[tuple[Any, ...], torch.Tensor] = {}
        self._fk_cache = PartFKCache()

    def get_joint_ids(self, name: Optional[str] = None, remove_mimic: bool = False) -> list[int]:
        """Joint ids of control part ``name`` (all joints when ``None``)."""
        if name is None:
            ids = list(range(self.dof))
        elif name not in self.control_parts:
            raise KeyError(f"{self.uid}: unknown control part {name!r}.{did_you_mean(name, self.control_parts)}")
        else:
            ids = list(self.control_parts[name])
        if remove_mimic:
            ids = [i for i in ids if i not in self.mimic_ids]
        return ids

    @property
    def active_joint_ids(self) -> list[int]:
        """Joints that are not mimics."""
        return [i for i in range(self.dof) if i not in self.mimic_ids]

    def get_proprioception(self) -> dict[str, torch.Tensor]:
        """``{"qpos", "qvel", "qf"}``, each (N, dof)."""
        return {"qpos": self.get_qpos(), "qvel": self.get_qvel(), "qf": self.get_qf()}

    def get_link_names(self, name: Optional[str] = None) -> list[str]:
        """Links moved by control part ``name`` (all links when ``None``)."""
        if name is None:
            return list(self.link_names)
        model = self.scene.model
        jnt_bodies = {int(model.jnt_bodyid[self._joint_ids[j]]) for j in self.get_joint_ids(name)}
        return [n for n, b in zip(self.link_names, self.body_ids.tolist()) if b in jnt_bodies]

    def compute_fk(
        self,
        qpos: Optional[torch.Tensor] = None,
        link_names: Any = None,
        env_ids: Any = None,
        to_matrix: bool = True,
        name: Optional[str] = None,
    ) -> torch.Tensor:
        """Forward kinematics in the env frame.

        With ``name`` (a control part with a solver) and no ``link_names``: the
        part's TCP pose, (n, 4, 4) (or (n, 7) xyz + wxyz with ``to_matrix=False``).
        ``qpos`` is then (n, k) part joint values or (n, dof) full joint values (the
        root link then follows the full qpos too); None uses the current ones.

        Otherwise: poses of ``link_names`` at ``qpos`` (n, dof), (n, L, 4, 4) (or
        (n, 4, 4) for one link name). Runs MuJoCo's kinematics on a scratch MjData
        per env, so the simulation state is untouched.
        """
        if name is not None and link_names is None:
            return self._compute_part_fk(qpos, name, env_ids, to_matrix)
        env = self._ids(env_ids)
        single = isinstance(link_names, str)
        links, _ = self.find_bodies(link_names if link_names is not None else self.link_names, preserve_order=True)
        bodies = self.body_ids[links].numpy()
        qpos = (
            self.get_qpos()[env] if qpos is None else torch.as_tensor(qpos, dtype=torch.float64).reshape(len(env), -1)
        )
        out = np.zeros((len(env), len(bodies), 7))
        data = mujoco.MjData(self.scene.model)
        adr = self.qpos_adr.numpy()
        current = self.state_route.read("qpos", env)  # host values on either route
        joints = qpos.detach().cpu().numpy()
        for k, e in enumerate(env.tolist()):
            data.qpos[:] = current[k]
            data.qpos[adr] = joints[k]
            mujoco.mj_kinematics(self.sim.get_model(e), data)
            out[k, :, :3], out[k, :, 3:] = data.xpos[bodies], data.xquat[bodies]
        pose = torch.as_tensor(out, dtype=torch.float32)
        pose = pose_to_matrix(pose) if to_matrix else pose
        return pose[:, 0] if single else pose

    # -- control part kinematics -------------------------------------------------------------
    def get_solver(self, name: Optional[str] = None) -> Any:
        """The kinematics solver of control part ``name`` (the only one when ``None``)."""
        if name is None and len(self.solvers) == 1:
            return next(iter(self.solvers.values()))
        if name not in self.solvers:
            have = list(self.solvers) or (
                "none; the robot config builds no solvers: add 'solver_cfg': {part: {'class_type': ...}} to it"
            )
            raise KeyError(f"{self.uid}: no kinematics solver for control part {name!r} (solvers: {have})")
        return self.solvers[name]

    def get_control_part_base_pose(
        self, name: Optional[str] = None, env_ids: Any = None, to_matrix: bool = True
    ) -> torch.Tensor:
        """Pose of the solver root link of part ``name`` in the env frame, (n, 4, 4) or (n, 7)."""
        return self.get_link_pose(self.get_solver(name).root_link_name, env_ids, to_matrix)

    def _fk_device(self, solver: Any) -> torch.device:
        """Where part FK runs: the sim's device for solvers with ``fk_on_device``, else the CPU."""
        return self.sim.device if getattr(solver, "fk_on_device", False) else torch.device("cpu")

    def _on(self, index: Any, device: torch.device) -> torch.Tensor:
        """A constant long index on ``device``, copied there once (no per-call host copy)."""
        key = (tuple(int(i) for i in index), device)
        out = self._index_cache.get(key)
        if out is None:
            out = self._index_cache[key] = torch.as_tensor(key[0], dtype=torch.long, device=device)
        return out

    def _rows(self, env_ids: Any, device: torch.device) -> Any:
        """Env rows of the sim's views: every row (a slice, no index copy) when ``env_ids`` is None."""
        return slice(None) if env_ids is None else self._ids(env_ids).to(device)

    def _part_qpos(self, solver: Any, qpos: Any, env_ids: Any, device: Any = "cpu") -> torch.Tensor:
        """(n, k) float64 part joint values on ``device`` from ``qpos`` (None, (n, k) or (n, dof))."""
        ids, device = list(solver.joint_ids), torch.device(device)
        if qpos is None:
            sim = self.sim
            q = sim.qpos[self._rows(env_ids, sim.device)][:, self._on(self.qpos_adr[ids].tolist(), sim.device)]
            return q.to(device, torch.float64)
        n = self.num_envs if env_ids is None else len(self._ids(env_ids))
        q = torch.as_tensor(qpos).detach().to(device, torch.float64)
        q = q.reshape(n, -1) if q.dim() != 1 or n == 1 else q.expand(n, -1)
        if q.shape[-1] == len(ids):
            return q
        if q.shape[-1] == self.dof:
            return q[:, self._on(ids, device)]
        raise ValueError(
            f"{self.uid}: qpos has {q.shape[-1]} values per env; expected {len(ids)} "
            f"(the part's joints) or {self.dof} (all joints)"
        )

    def _base_matrix(self, solver: Any, qpos: Any, env_ids: Any, device: Any = "cpu") -> torch.Tensor:
        """(n, 4, 4) float64 root link pose on ``device``; follows ``qpos`` when it is a full joint vector."""
        q = None if qpos is None else torch.as_tensor(qpos)
        if q is not None and q.shape[-1] == self.dof and q.shape[-1] != len(solver.joint_ids):
            env = self._ids(env_ids)
            base = self.compute_fk(q.reshape(len(env), -1), link_names=[solver.root_link_name], env_ids=env)[:, 0]
            return base.to(device, torch.float64)
        body = self._link_body.get(solver.root_link_name)
        if body is None:
            body = self._link_body[solver.root_link_name] = int(
                self.body_ids[self.find_bodies(solver.root_link_name)[0][0]]
            )
        sim, rows = self.sim, self._rows(env_ids, self.sim.device)
        pose = torch.cat((sim.xpos[rows, body], sim.xquat[rows, body]), -1)
        return pose_to_matrix(pose.to(device, torch.float64))

    def _part_fk64(self, name: Optional[str], qpos: Any, env_ids: Any) -> torch.Tensor:
        """(n, 4, 4) float64 TCP pose of part ``name`` in the env frame, where FK runs
        (the sim's device for solvers with ``fk_on_device``, else the CPU).

        With ``qpos`` and ``env_ids`` None on the host route (the CPU backends' state), the
        result of the last call is reused while its inputs (joint values, root link pose,
        solver and TCP) are unchanged.
        """
        solver = self.get_solver(name)
        device = self._fk_device(solver)
        q = self._part_qpos(solver, qpos, env_ids, device)
        base = self._base_matrix(solver, qpos, env_ids, device)
        current = qpos is None and env_ids is None and device.type == "cpu" and self.state_route.host
        hit = self._fk_cache.get(name, solver, q, base) if current else None
        if hit is not None:
            return hit
        pose = base @ torch.as_tensor(solver.get_fk(q)).to(device, torch.float64)
        if current:
            self._fk_cache.put(name, solver, q, base, pose)
        return pose

    def _compute_part_fk(self, qpos: Any, name: str, env_ids: Any, to_matrix: bool) -> torch.Tensor:
        pose = self._out(self._part_fk64(name, qpos, env_ids))
        return pose if to_matrix else matrix_to_pose(pose)

    def compute_ik(
        self, pose: Any, joint_seed: Optional[torch.Tensor] = None, name: Optional[str] = None, env_ids: Any = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Inverse kinematics of control part ``name``'s TCP for ``env_ids``.

        Args:
            pose: (n, 4, 4) or (n, 7) (xyz + wxyz) TCP targets in the env frame.
            joint_seed: (n, k) part or (n, dof) full joint values to start from;
                None starts from the current joint positions.
            name: the control part (the only solver's part when None).
            env_ids: the envs the targets are for (all when None).

        Returns:
            ``(success (n,) bool, qpos (n, k))``; ``qpos`` respects the joint limits
            and is in the order of ``robot.get_solver(name).joint_ids``.
        """
        solver = self.get_solver(name)
        on_device, device = ik_route(solver, self.state_route.host, self.sim.device)
        target = torch.as_tensor(pose).detach().to(device, torch.float64)
        if target.shape[-1] == 7:
            target = pose_to_matrix(target)
        target = target.reshape(len(self._ids(env_ids)), 4, 4)
        seed = self._part_qpos(solver, joint_seed, env_ids, device)
        local = transform_inverse(self._base_matrix(solver, None, env_ids, device)) @ target
        success, qpos = solve_part_ik(solver, local, seed, on_device)
        return success.to(self.device), self._out(qpos)


class PartFKCache:
    """The last current-state part FK of each control part, reused while its inputs are equal.

    The key is what the pose is a function of: the solver object, its ``chain`` and ``tcp``,
    the part's joint values and the root link pose, compared by value (so a reset, a state
    write or a step within the control step that moves anything is a miss). Only solvers
    with ``fk_on_device`` are cached (their FK depends on nothing else), and only on the
    host route: on an accelerator the value comparison would wait for the device, which
    costs more than recomputing there.
    """

    def __init__(self) -> None:
        self._last: dict[Optional[str], tuple[Any, ...]] = {}

    def get(self, part: Optional[str], solver: Any, q: torch.Tensor, base: torch.Tensor) -> Optional[torch.Tensor]:
        """The cached pose, or None when anything it depends on differs."""
        last = self._last.get(part)
        if last is None or not getattr(solver, "fk_on_device", False):
            return None
        now = (solver, getattr(solver, "chain", None), getattr(solver, "tcp", None), q, base)
        return last[-1] if all(_same(a, b) for a, b in zip(last, now)) else None

    def put(self, part: Optional[str], solver: Any, q: torch.Tensor, base: torch.Tensor, pose: torch.Tensor) -> None:
        """Remember ``pose`` (float64; callers get converted copies) for these inputs."""
        if getattr(solver, "fk_on_device", False):
            tcp = getattr(solver, "tcp", None)
            tcp = None if tcp is None else torch.as_tensor(tcp).clone()
            self._last[part] = (solver, getattr(solver, "chain", None), tcp, q.clone(), base.clone(), pose)


def _same(was: Any, now: Any) -> bool:
    """Tensors by value (shape and every element), anything else by identity."""
    if isinstance(was, torch.Tensor) and now is not None:
        now = torch.as_tensor(now)
        return was.shape == now.shape and bool(torch.equal(was, now.to(was.device, was.dtype)))
    return was is now
