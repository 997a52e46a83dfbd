"""Reference IK on MuJoCo's own Jacobians (``mj_jac``), one scratch MjData, env by env.

Same algorithm and API as :class:`DLSSolver` (damped least squares, joint-limit
active set, batched random restarts); only FK and the Jacobian come from
``mj_kinematics`` + ``mj_comPos`` + ``mj_jac`` in a Python loop over the batch.
It exists to measure the batched torch chain against (``benchmarks/ik_throughput.py``).
"""

from __future__ import annotations

from typing import Optional, Sequence

import mujoco
import numpy as np
import torch

from embodichain_robots.kinematics.chain import SerialChain
from embodichain_robots.kinematics.solver import DLSSolver, IKSolverCfg, _host

_F64 = torch.float64


class MjDLSSolver(DLSSolver):
    """:class:`DLSSolver` with FK and Jacobians from MuJoCo (slower; a reference)."""

    #: FK runs on the host (MuJoCo); the robot hands it CPU joint values.
    fk_on_device = False
    #: IK runs on the host too (:meth:`DLSSolver.get_ik` only).
    ik_on_device = False

    def __init__(
        self,
        cfg: IKSolverCfg,
        chain: SerialChain,
        model: mujoco.MjModel,
        prefix: str = "",
        joint_ids: Optional[Sequence[int]] = None,
    ):
        super().__init__(cfg, chain, joint_ids)
        self.model = model
        self.data = mujoco.MjData(model)
        self.root = model.body(prefix + cfg.root_link_name).id
        self.end = model.body(prefix + cfg.end_link_name).id
        joints = [model.joint(prefix + name) for name in chain.joint_names]
        self.qpos_adr = np.array([j.qposadr[0] for j in joints])
        self.dof_adr = np.array([j.dofadr[0] for j in joints])

    @classmethod
    def from_model(
        cls, cfg: IKSolverCfg, model: mujoco.MjModel, prefix: str = "", joint_ids: Optional[Sequence[int]] = None
    ) -> "MjDLSSolver":
        chain = SerialChain.from_model(model, cfg.root_link_name, cfg.end_link_name, prefix)
        return cls(cfg, chain, model, prefix, joint_ids)

    def get_fk(self, qpos: torch.Tensor) -> torch.Tensor:
        return self.fk_jacobian(_host(qpos).reshape(-1, self.dof))[0]

    def fk_jacobian(self, qpos: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        m, d = self.model, self.data
        q = qpos.detach().cpu().numpy()
        tcp = self.tcp.numpy()
        poses, jacs = np.zeros((len(q), 4, 4)), np.zeros((len(q), 6, self.dof))
        jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        for k in range(len(q)):
            d.qpos[self.qpos_adr] = q[k]
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            rot_root, rot_end = d.xmat[self.root].reshape(3, 3), d.xmat[self.end].reshape(3, 3)
            point = d.xpos[self.end] + rot_end @ tcp[:3, 3]
            mujoco.mj_jac(m, d, jacp, jacr, point, self.end)
            poses[k, :3, :3] = rot_root.T @ rot_end @ tcp[:3, :3]
            poses[k, :3, 3] = rot_root.T @ (point - d.xpos[self.root])
            jacs[k, :3] = rot_root.T @ jacp[:, self.dof_adr]
            jacs[k, 3:] = rot_root.T @ jacr[:, self.dof_adr]
        poses[:, 3, 3] = 1.0
        return torch.from_numpy(poses), torch.from_numpy(jacs)
