"""The env's own reads and writes of the robot's active joints, resolved once at build.

:class:`RobotIO` serves phase 2 of ``step`` (joint commands into ``ctrl`` /
``qfrc_applied``) and the default ``robot`` observation of phase 6. Everything that
does not depend on the state (addresses, which action columns drive which
actuators, whether the addresses are one contiguous run) is worked out here once.
On a backend with host arrays (``sim.capabilities.host_arrays`` on the CPU) reads
and writes go through numpy views of the simulation's memory: a slice or fancy
index there costs ~1 us where the same torch op costs 3-5 us. Other backends get
the same values through the torch views.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np
import torch

_Sel = Union[slice, np.ndarray]


def _selector(adr: np.ndarray) -> _Sel:
    """A slice when ``adr`` is one ascending run of addresses (a view), else the index array."""
    adr = np.asarray(adr, dtype=np.int64).reshape(-1)
    if adr.size and np.array_equal(adr, np.arange(adr[0], adr[0] + adr.size)):
        return slice(int(adr[0]), int(adr[0]) + adr.size)
    return adr


class RobotIO:
    """Active-joint commands and observations of one env's robot.

    Args:
        sim: the simulation backend.
        robot: the env's robot entity.
        active_joint_ids: the robot's joint ids the env acts on.
        num_envs: the batch size.
    """

    def __init__(self, sim: Any, robot: Any, active_joint_ids: list[int], num_envs: int):
        aid = torch.as_tensor(active_joint_ids, dtype=torch.long)
        self.sim, self.num_envs = sim, int(num_envs)
        self.active_joint_ids = list(active_joint_ids)
        self.n_active, self.dof = len(aid), int(robot.dof)
        self.qpos_adr, self.dof_adr = robot.qpos_adr[aid], robot.dof_adr[aid]
        self.host = (
            bool(getattr(getattr(sim, "capabilities", None), "host_arrays", False))
            and getattr(sim, "device", torch.device("cpu")).type == "cpu"
        )
        self._qpos_sel, self._dof_sel = _selector(self.qpos_adr.numpy()), _selector(self.dof_adr.numpy())
        # per command kind: (driven columns of the action, their actuator ids)
        self.drive_targets = {
            key: ((acts >= 0), acts[acts >= 0])
            for key, acts in (("qpos", robot.pos_act[aid]), ("qvel", robot.vel_act[aid]))
        }
        self._drive_np = {
            key: (None if bool(cols.all()) else cols.numpy(), acts.numpy())
            for key, (cols, acts) in self.drive_targets.items()
        }

    # -- phase 2: commands ------------------------------------------------------------------------
    def write(self, key: str, value: Any) -> None:
        """Write joint command ``key`` (``qpos``/``qvel`` targets, ``qf`` efforts) of every env.

        ``value`` is ``(num_envs, n)`` or ``(n,)`` with ``n`` the active joints' or all
        joints' count.

        Raises:
            ValueError: ``n`` is neither.
        """
        value = torch.as_tensor(value)
        if value.dim() == 1:
            value = value.unsqueeze(0).expand(self.num_envs, -1)
        if value.shape[-1] == self.dof and self.dof != self.n_active:
            value = value[:, self.active_joint_ids]
        elif value.shape[-1] != self.n_active:
            raise ValueError(
                f"{key} command has {value.shape[-1]} values per env; expected {self.n_active} "
                f"(active joints) or {self.dof} (all joints)"
            )
        if self.host and value.device.type == "cpu" and value.dtype in (torch.float32, torch.float64):
            self._write_host(key, value.detach().numpy())
            return
        value = value.to(torch.float64)
        if key == "qf":
            self.sim.qfrc_applied[:, self.dof_adr] = value
            return
        columns, actuators = self.drive_targets[key]
        self.sim.ctrl[:, actuators] = value[:, columns]

    def _write_host(self, key: str, value: np.ndarray) -> None:
        arrays = self.sim.arrays
        if key == "qf":
            arrays["qfrc_applied"][:, self._dof_sel] = value
            return
        columns, actuators = self._drive_np[key]
        arrays["ctrl"][:, actuators] = value if columns is None else value[:, columns]

    # -- phase 6: the default observation ------------------------------------------------------------
    def observe(self) -> dict[str, torch.Tensor]:
        """``{"qpos", "qvel", "qf"}`` of the active joints, float32 ``(num_envs, n_active)``,
        ``qf`` = actuator + applied joint forces; fresh tensors every call."""
        sim = self.sim
        if self.host:
            qfrc = sim.qfrc_actuator.numpy()  # the attribute read runs the lazy forward first
            arrays, dof = sim.arrays, self._dof_sel
            return {
                "qpos": torch.from_numpy(arrays["qpos"][:, self._qpos_sel].astype(np.float32)),
                "qvel": torch.from_numpy(arrays["qvel"][:, dof].astype(np.float32)),
                "qf": torch.from_numpy((qfrc[:, dof] + arrays["qfrc_applied"][:, dof]).astype(np.float32)),
            }
        dof = self.dof_adr
        return {
            "qpos": sim.qpos[:, self.qpos_adr].float(),
            "qvel": sim.qvel[:, dof].float(),
            "qf": (sim.qfrc_actuator[:, dof] + sim.qfrc_applied[:, dof]).float(),
        }
