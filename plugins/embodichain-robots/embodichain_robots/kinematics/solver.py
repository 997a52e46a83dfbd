"""Batched IK for a control part: damped least squares on a torch serial chain.

Every env's target is solved at once: each iteration evaluates FK and the
geometric Jacobian of the whole batch (:class:`SerialChain`), takes a damped
Gauss-Newton step ``dq = J^T (J J^T + lambda^2 I)^-1 e`` (clamped to
``max_step``), and clamps to the joint limits. Envs still off target after
``max_iterations`` restart from ``num_samples`` random joint values each (the
best of a larger random pool, ranked by FK error), solved as one batch, for up
to ``num_restarts`` rounds. Poses are in the chain's root-link frame; the
robot converts from the env frame (:meth:`Robot.compute_ik`).

:meth:`DLSSolver.get_ik` runs on the CPU (it reads convergence back to stop early and to pick
the envs to restart). :meth:`DLSSolver.get_ik_on_device` runs where its target is and never
waits for the device: every env takes ``max_iterations`` iterations (a converged env's step
is masked to zero, so its joints stay where they converged: the same values as ``get_ik``'s
first attempt) and no random restarts (they need the unconverged envs' ids on the host).

Example:
    >>> solver = DLSSolver.from_model(IKSolverCfg(root_link_name="base", end_link_name="hand"), model)
    >>> success, qpos = solver.get_ik(target, qpos_seed=seed)      # (N,), (N, n)
"""

from __future__ import annotations

import hashlib
from typing import Any, Optional, Sequence

import mujoco
import torch

from embodichain_robots.kinematics.chain import SerialChain
from embodichain_robots.kinematics.ik_math import (
    one_thread,
    rotation_angle,
    rotation_error,
    sample_joint_values,
    single_threaded,
)
from embodichain_robots.kinematics.solver_cfg import IKSolverCfg

__all__ = [
    "DLSSolver",
    "IKSolverCfg",
    "rotation_angle",
    "rotation_error",
    "sample_joint_values",
    "single_threaded",
]

_F64 = torch.float64


def _host(values: Any) -> torch.Tensor:
    """``values`` as a float64 CPU tensor (:meth:`DLSSolver.get_ik`, Jacobians and pose errors
    run on the CPU whatever the sim device)."""
    return torch.as_tensor(values).to("cpu", _F64)


class DLSSolver:
    """Batched damped-least-squares IK of one serial chain (see module docstring).

    FK (:meth:`get_fk`) and :meth:`get_ik_on_device` run where their input is; :meth:`get_ik`
    and the Jacobian on the CPU.
    """

    #: ``get_fk`` computes on its input's device (the robot keeps FK on the sim device).
    fk_on_device: bool = True
    #: :meth:`get_ik_on_device` solves on its input's device with no host read.
    ik_on_device: bool = True

    def __init__(self, cfg: IKSolverCfg, chain: SerialChain, joint_ids: Optional[Sequence[int]] = None):
        self.cfg = cfg
        self.chain = chain
        self.joint_names = list(chain.joint_names)
        self.joint_ids = list(joint_ids) if joint_ids is not None else list(range(chain.n))
        self.root_link_name, self.end_link_name = cfg.root_link_name, cfg.end_link_name
        self.tcp = torch.as_tensor(cfg.tcp, dtype=_F64).reshape(4, 4)
        self._tcp_cache: Optional[tuple[tuple[Any, ...], torch.Tensor]] = None

    @classmethod
    def from_model(
        cls, cfg: IKSolverCfg, model: mujoco.MjModel, prefix: str = "", joint_ids: Optional[Sequence[int]] = None
    ) -> "DLSSolver":
        """Build from a compiled model whose names carry ``prefix``."""
        chain = SerialChain.from_model(model, cfg.root_link_name, cfg.end_link_name, prefix)
        if cfg.joint_names is not None and list(cfg.joint_names) != chain.joint_names:
            raise ValueError(f"solver joints {cfg.joint_names} differ from the chain's {chain.joint_names}")
        return cls(cfg, chain, joint_ids)

    @classmethod
    def from_config(cls, cfg: Any, robot: Any, part: str) -> "DLSSolver":
        """The solver of control part ``part`` of a built robot, from a ``solver_cfg`` entry
        (the solver-registry contract; see ``kinematics.factory.solver_from_config``)."""
        from embodichain_robots.kinematics.factory import solver_from_config

        return solver_from_config(cls, cfg, robot, part)

    # -- properties ----------------------------------------------------------------------
    @property
    def dof(self) -> int:
        """Number of chain joints."""
        return self.chain.n

    @property
    def qpos_limits(self) -> torch.Tensor:
        """(n, 2) joint limits."""
        return self.chain.limits.clone()

    def set_tcp(self, tcp: Any) -> None:
        """Replace the 4x4 TCP (in the end link frame)."""
        self.tcp = torch.as_tensor(tcp, dtype=_F64).reshape(4, 4).clone()

    def get_tcp(self) -> torch.Tensor:
        """The 4x4 TCP in the end link frame."""
        return self.tcp.clone()

    # -- kinematics ----------------------------------------------------------------------
    @one_thread
    def get_fk(self, qpos: torch.Tensor) -> torch.Tensor:
        """(N, 4, 4) float64 TCP pose in the root link frame at ``qpos`` (N, n).

        Computed where ``qpos`` is (CPU or an accelerator): no host copy, no sync
        (``fk_on_device``); the chain's constants and the TCP are copied to a device once.
        """
        q = torch.as_tensor(qpos)
        q = q.reshape(-1, self.dof).to(_F64)
        return self.chain.fk(q, self._tcp_on(q.device))

    def _tcp_on(self, device: torch.device) -> torch.Tensor:
        """``self.tcp`` on ``device``, cached until the TCP changes (``set_tcp``, a new or
        an in-place edited ``tcp`` tensor)."""
        key = (device, id(self.tcp), self.tcp._version)
        cached = self._tcp_cache
        if cached is None or cached[0] != key:
            cached = (key, self.tcp.to(device, _F64))
            self._tcp_cache = cached
        return cached[1]

    @one_thread
    def get_jacobian(self, qpos: torch.Tensor) -> torch.Tensor:
        """(N, 6, n) geometric TCP Jacobian (linear rows first) in the root frame."""
        return self.fk_jacobian(_host(qpos).reshape(-1, self.dof))[1]

    def fk_jacobian(self, qpos: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """``(TCP pose (N, 4, 4), Jacobian (N, 6, n))`` in the root frame (float64 input),
        computed where ``qpos`` is."""
        return self.chain.jacobian(qpos, self._tcp_on(qpos.device))

    @one_thread
    def pose_error(self, target: torch.Tensor, qpos: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(position error (N,) in m, rotation error (N,) in rad) of ``qpos`` w.r.t. ``target``."""
        pose = self.get_fk(_host(qpos))
        target = _host(target)
        pos = torch.linalg.norm(target[:, :3, 3] - pose[:, :3, 3], dim=-1)
        return pos, rotation_angle(target[:, :3, :3], pose[:, :3, :3])

    @one_thread
    def get_ik(
        self, target: torch.Tensor, qpos_seed: Optional[torch.Tensor] = None, num_restarts: Optional[int] = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Solve every target of the batch.

        Args:
            target: (N, 4, 4) TCP targets in the root link frame.
            qpos_seed: (N, n) start joint values (clamped to the limits); None
                starts from the middle of the limits.
            num_restarts: overrides ``cfg.num_restarts``.

        Returns:
            ``(success (N,) bool, qpos (N, n) float64)``; where ``success`` is
            False, ``qpos`` is the best attempt found.
        """
        target = _host(target).reshape(-1, 4, 4)
        n = target.shape[0]
        if qpos_seed is None:
            seed = self._middle().expand(n, -1)
        else:
            seed = _host(qpos_seed).reshape(n, self.dof)
        seed = torch.minimum(torch.maximum(seed, self.chain.limits[:, 0]), self.chain.limits[:, 1])
        q, ok, err = self._solve(target, seed, early_exit=True)
        restarts = self.cfg.num_restarts if num_restarts is None else int(num_restarts)
        todo = torch.nonzero(~ok).flatten()
        for round_ in range(restarts):
            if len(todo) == 0:
                break
            k = max(int(self.cfg.num_samples), 1)
            owners = todo.repeat_interleave(k)
            q_try, ok_try, err_try = self._solve(
                target[owners], self._restart_seeds(target[todo], k, round_), early_exit=True
            )
            best = err_try.reshape(-1, k).argmin(-1) + torch.arange(len(todo)) * k
            better = err_try[best] < err[todo]
            q[todo[better]], err[todo[better]] = q_try[best][better], err_try[best][better]
            ok[todo] |= ok_try.reshape(-1, k).any(-1)
            todo = todo[~ok[todo]]
        return ok, q

    @one_thread
    def get_ik_on_device(self, target: torch.Tensor, qpos_seed: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Solve every target of the batch on its device, without waiting for the device.

        The DLS iterations of :meth:`get_ik`'s first attempt with a fixed count
        (``max_iterations``; converged envs are masked, not awaited) and no random restarts.
        Where ``get_ik`` succeeds without a restart, the results are the same.

        Args:
            target: (N, 4, 4) TCP targets in the root link frame, on the device to solve on.
            qpos_seed: (N, n) start joint values (clamped to the limits).

        Returns:
            ``(success (N,) bool, qpos (N, n) float64)`` on the target's device; where
            ``success`` is False, ``qpos`` is where the iterations ended.
        """
        target = target.to(_F64).reshape(-1, 4, 4)
        lim = self.chain.on(target.device).limits
        seed = qpos_seed.to(target.device, _F64).reshape(target.shape[0], self.dof)
        seed = torch.minimum(torch.maximum(seed, lim[:, 0]), lim[:, 1])
        q, ok, _ = self._solve(target, seed, early_exit=False)
        return ok, q

    def _restart_seeds(self, target: torch.Tensor, k: int, round_: int = 0) -> torch.Tensor:
        """(len(target) * k, n) seeds: the ``k`` best of ``pool_factor * k`` random samples
        per target, ranked by their TCP pose error (one cheap batched FK)."""
        pool = max(int(self.cfg.pool_factor), 1) * k
        cand = torch.cat([sample_joint_values(self.chain.limits, pool, self._target_rng(t, round_)) for t in target])
        pose = self.chain.fk(cand, self.tcp).reshape(len(target), pool, 4, 4)
        pos = torch.linalg.norm(pose[..., :3, 3] - target[:, None, :3, 3], dim=-1)
        rot = rotation_angle(target[:, None, :3, :3], pose[..., :3, :3])
        best = (pos + self.cfg.rot_weight * rot).topk(k, dim=-1, largest=False).indices
        picked = cand.reshape(len(target), pool, -1).gather(1, best[..., None].expand(-1, -1, self.dof))
        return picked.reshape(-1, self.dof)

    def _target_rng(self, target: torch.Tensor, round_: int) -> torch.Generator:
        """A generator seeded by ``cfg.seed``, the restart round and the target pose's bytes: an
        env's restarts depend on its own target alone, never on which other envs needed some."""
        data = target.to(_F64).contiguous().numpy().tobytes() + int(round_).to_bytes(4, "little")
        digest = hashlib.blake2b(
            data, digest_size=8, key=int(self.cfg.seed).to_bytes(8, "little", signed=True)
        ).digest()
        return torch.Generator().manual_seed(int.from_bytes(digest, "little") >> 1)

    def _middle(self) -> torch.Tensor:
        """(n,) middle of the (finite, +-pi clipped) joint ranges."""
        lim = self.chain.limits
        return (lim[:, 0].clamp(min=-torch.pi) + lim[:, 1].clamp(max=torch.pi)) / 2

    @staticmethod
    def _step(
        jac: torch.Tensor, err: torch.Tensor, q: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor, eye: torch.Tensor
    ) -> torch.Tensor:
        """A DLS step with the joints pushed against a limit frozen (active set)."""
        grad = (jac.transpose(1, 2) @ err[..., None])[..., 0]
        blocked = ((q <= lo + 1e-9) & (grad < 0)) | ((q >= hi - 1e-9) & (grad > 0))
        jac = jac * (~blocked)[:, None, :]
        # solve_ex: no error check, which would wait for the device (J J^T + lambda^2 I is positive definite)
        solved = torch.linalg.solve_ex(jac @ jac.transpose(1, 2) + eye, err[..., None], check_errors=False)[0]
        return (jac.transpose(1, 2) @ solved)[..., 0]

    def _solve(
        self, target: torch.Tensor, q: torch.Tensor, early_exit: bool
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """DLS iterations from ``q`` on its device: (qpos, converged, combined error).
        ``early_exit`` stops once every env converged (a host read per iteration);
        without it all ``max_iterations`` run, converged envs standing still."""
        consts = self.chain.on(q.device)
        lo, hi = consts.limits[:, 0], consts.limits[:, 1]
        eye = torch.eye(6, dtype=_F64, device=q.device) * self.cfg.damping**2
        t_rot, t_pos = target[:, :3, :3], target[:, :3, 3]
        pose = None
        for _ in range(self.cfg.max_iterations):
            pose, jac = self.fk_jacobian(q)
            err = torch.cat((t_pos - pose[:, :3, 3], rotation_error(t_rot, pose[:, :3, :3])), -1)
            ok = (err[:, :3].norm(dim=-1) < self.cfg.pos_tol) & (err[:, 3:].norm(dim=-1) < self.cfg.rot_tol)
            if early_exit and bool(ok.all()):
                break
            step = self._step(jac, err, q, lo, hi, eye) * (~ok)[:, None]
            scale = (self.cfg.max_step / step.abs().amax(-1).clamp(min=1e-12)).clamp(max=1.0)
            q = torch.minimum(torch.maximum(q + step * scale[:, None], lo), hi)
            pose = None
        pose = self.get_fk(q) if pose is None else pose
        pos_err = torch.linalg.norm(t_pos - pose[:, :3, 3], dim=-1)
        rot_err = rotation_angle(t_rot, pose[:, :3, :3])
        ok = (pos_err < self.cfg.pos_tol) & (rot_err < self.cfg.rot_tol)
        return q, ok, pos_err + self.cfg.rot_weight * rot_err
