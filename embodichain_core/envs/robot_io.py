"""The env's own reads and writes of the robot's active joints, resolved once at build.

:class:`RobotIO` serves phase 2 of ``step`` (joint commands into ``ctrl`` /
``qfrc_applied``) and the default ``robot`` observation of phase 6. Everything that
does not depend on the state (addresses, which action columns drive which
actuators, whether the addresses are one run with one stride, so that a slice is a
view) is worked out here once. On a backend with host arrays
(``sim.capabilities.host_arrays`` on the CPU) reads and writes go through numpy views
of the simulation's memory: a slice or fancy index there costs ~1 us where the same
torch op costs 3-5 us, and a float32 ``(num_envs, n_active)`` action is written into
a view kept from step to step (remade when the backend rebinds ``sim.arrays``). Other
backends get the same values through the torch views.
"""

from __future__ import annotations

from typing import Any, Optional, Union

import numpy as np
import torch

_Sel = Union[slice, np.ndarray]


def _selector(adr: np.ndarray) -> _Sel:
    """A slice when ``adr`` is an ascending run of addresses with one stride (a view: ``3, 4, 5``
    or the position actuators ``0, 2, 4`` of interleaved position/velocity pairs), else the
    index array."""
    adr = np.asarray(adr, dtype=np.int64).reshape(-1)
    if not adr.size:
        return adr
    step = int(adr[1] - adr[0]) if adr.size > 1 else 1
    if step > 0 and np.array_equal(adr, adr[0] + step * np.arange(adr.size)):
        return slice(int(adr[0]), int(adr[-1]) + 1, step if step > 1 else None)
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
            key: (None if bool(cols.all()) else cols.numpy(), _selector(acts.numpy()))
            for key, (cols, acts) in self.drive_targets.items()
        }
        self._shape = (self.num_envs, self.n_active)  # the command shape of the fast path
        self._targets: dict[str, np.ndarray] = {}  # command key -> numpy view it is written into
        self._arrays_of_targets: Any = None  # the ``sim.arrays`` mapping those views come from
        self._qfrc: tuple[Any, Any] = (None, None)  # (the qfrc_actuator view, its numpy array)

    # -- phase 2: commands ------------------------------------------------------------------------
    def write(self, key: str, value: Any, host_array: Optional[np.ndarray] = None) -> None:
        """Write joint command ``key`` (``qpos``/``qvel`` targets, ``qf`` efforts) of every env.

        ``value`` is ``(num_envs, n)`` or ``(n,)`` with ``n`` the active joints' or all
        joints' count. ``host_array``: the numpy view of a CPU ``value``, when the caller
        has it already.

        Raises:
            ValueError: ``n`` is neither.
        """
        if (
            type(value) is torch.Tensor
            and value.shape == self._shape
            and value.dtype is torch.float32
            and self.host
            and value.is_cpu
            and not value.requires_grad
        ):
            # the common case: one action row per env
            self._write_host(key, value.numpy() if host_array is None else host_array)
            return
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
        if self.sim.arrays is not self._arrays_of_targets:
            self._bind_targets()
        target = self._targets.get(key)
        if target is not None:
            target[...] = value  # a view: every column driven, actuators one strided run
            return
        if key == "qf":
            self.sim.arrays["qfrc_applied"][:, self._dof_sel] = value
            return
        columns, actuators = self._drive_np[key]
        self.sim.arrays["ctrl"][:, actuators] = value if columns is None else value[:, columns]

    def _bind_targets(self) -> None:
        """The numpy views commands are written into (a backend that rebuilds its arrays,
        e.g. on switching to per-env models, gets new ones)."""
        arrays = self.sim.arrays
        self._targets = {}
        if isinstance(self._dof_sel, slice):
            self._targets["qf"] = arrays["qfrc_applied"][:, self._dof_sel]
        for key, (columns, actuators) in self._drive_np.items():
            if columns is None and isinstance(actuators, slice):
                self._targets[key] = arrays["ctrl"][:, actuators]
        self._arrays_of_targets = arrays

    # -- phase 6: the default observation ------------------------------------------------------------
    def observe(self) -> dict[str, torch.Tensor]:
        """``{"qpos", "qvel", "qf"}`` of the active joints, float32 ``(num_envs, n_active)``,
        ``qf`` = actuator + applied joint forces; fresh tensors every call."""
        sim = self.sim
        if self.host:
            view = sim.view("qfrc_actuator")  # the read runs the lazy forward first
            if view is not self._qfrc[0]:
                self._qfrc = (view, view.numpy())
            arrays, dof = sim.arrays, self._dof_sel
            qf = self._qfrc[1][:, dof] + arrays["qfrc_applied"][:, dof]
            return {
                "qpos": torch.from_numpy(arrays["qpos"][:, self._qpos_sel].astype(np.float32)),
                "qvel": torch.from_numpy(arrays["qvel"][:, dof].astype(np.float32)),
                "qf": torch.from_numpy(qf.astype(np.float32)),
            }
        dof = self.dof_adr
        return {
            "qpos": sim.qpos[:, self.qpos_adr].float(),
            "qvel": sim.qvel[:, dof].float(),
            "qf": (sim.qfrc_actuator[:, dof] + sim.qfrc_applied[:, dof]).float(),
        }
