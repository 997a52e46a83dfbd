"""The env's one bridge between the simulation's state and torch for the robot's joints.

:class:`RobotIO` serves phase 2 of ``step`` (joint commands into ``ctrl`` /
``qfrc_applied``) and the default ``robot`` observation of phase 6. Everything that
does not depend on the state (addresses, which action columns drive which
actuators, whether the addresses are one run with one stride, so that a slice is a
view) is worked out here once, and so is the route the data takes, the one the
entities take (:func:`~embodichain_core.sim.backend.state_route.state_route`): on a
backend whose state lives in host memory (``sim.capabilities.host_arrays``) commands
are written into, and observations read from, numpy views of that memory (cheaper per
call than the same torch indexing on the small batches of the CPU backend); any other
backend gets the same values through its torch views. Callers see torch tensors either
way.
"""

from __future__ import annotations

from typing import Any, Union

import numpy as np
import torch

from embodichain_core.sim.backend.state_route import state_route

_Sel = Union[slice, np.ndarray]
_FLOATS = (torch.float32, torch.float64)


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

    Attributes:
        host: whether data moves through the backend's numpy views (chosen at build:
            where the backend has them, ``sim.capabilities.host_arrays``), else its torch views.
        drive_targets: per command kind (``qpos``, ``qvel``): the action columns that drive
            an actuator, and those actuators' ids.
    """

    def __init__(self, sim: Any, robot: Any, active_joint_ids: list[int], num_envs: int):
        aid = torch.as_tensor(active_joint_ids, dtype=torch.long)
        self.sim, self.num_envs = sim, int(num_envs)
        self.active_joint_ids = list(active_joint_ids)
        self.n_active, self.dof = len(aid), int(robot.dof)
        self.qpos_adr, self.dof_adr = robot.qpos_adr[aid], robot.dof_adr[aid]
        self.host = state_route(sim, sim.device).host
        self.drive_targets = {
            key: ((acts >= 0), acts[acts >= 0])
            for key, acts in (("qpos", robot.pos_act[aid]), ("qvel", robot.vel_act[aid]))
        }
        self._shape = (self.num_envs, self.n_active)  # a command of this shape is written as it is
        if self.host:
            self._bind_host_views()
            self._write, self._observe = self._write_host, self._observe_host
        else:
            self._bind_device_indices()
            self._write, self._observe = self._write_tensor, self._observe_tensor

    def _bind_device_indices(self) -> None:
        """The indices of the tensor route, on the sim's device once (a slice where the
        addresses are one strided run): no host index is copied to the device per call."""
        device = self.sim.device

        def on_device(adr: torch.Tensor) -> Union[slice, torch.Tensor]:
            sel = _selector(adr.numpy())
            return sel if isinstance(sel, slice) else torch.as_tensor(sel, dtype=torch.long, device=device)

        self._qpos_idx, self._dof_idx = on_device(self.qpos_adr), on_device(self.dof_adr)
        self._drive_dev = {
            key: (None if bool(cols.all()) else on_device(torch.nonzero(cols).flatten()), on_device(acts))
            for key, (cols, acts) in self.drive_targets.items()
        }

    def _bind_host_views(self) -> None:
        """The numpy views of the host route, made once (the backend's views are persistent):
        where a command's columns map to one strided run of ``ctrl`` / ``qfrc_applied``, the
        view it is written into as a whole."""
        arrays = self.sim.arrays
        self._qpos_sel, self._dof_sel = _selector(self.qpos_adr.numpy()), _selector(self.dof_adr.numpy())
        self._drive_np = {
            key: (None if bool(cols.all()) else cols.numpy(), _selector(acts.numpy()))
            for key, (cols, acts) in self.drive_targets.items()
        }
        self._targets: dict[str, np.ndarray] = {}
        if isinstance(self._dof_sel, slice):
            self._targets["qf"] = arrays["qfrc_applied"][:, self._dof_sel]
        for key, (columns, actuators) in self._drive_np.items():
            if columns is None and isinstance(actuators, slice):
                self._targets[key] = arrays["ctrl"][:, actuators]
        self._qfrc_actuator = self.sim.view("qfrc_actuator").numpy()

    # -- phase 2: commands ------------------------------------------------------------------------
    def write(self, key: str, value: Any) -> None:
        """Write joint command ``key`` (``qpos``/``qvel`` targets, ``qf`` efforts) of every env.

        ``value`` is ``(num_envs, n)`` or ``(n,)`` with ``n`` the active joints' or all
        joints' count.

        Raises:
            ValueError: ``n`` is neither.
        """
        if not (type(value) is torch.Tensor and value.shape == self._shape and value.dtype in _FLOATS):
            value = self._shaped(key, value)
        self._write(key, value.detach() if value.requires_grad else value)

    def _shaped(self, key: str, value: Any) -> torch.Tensor:
        """``value`` as a float ``(num_envs, n_active)`` tensor."""
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
        return value if value.dtype in _FLOATS else value.to(torch.float64)

    def _write_tensor(self, key: str, value: torch.Tensor) -> None:
        sim = self.sim
        value = value.to(device=sim.device, dtype=sim.dtype)
        if key == "qf":
            sim.qfrc_applied[:, self._dof_idx] = value
            return
        columns, actuators = self._drive_dev[key]
        sim.ctrl[:, actuators] = value if columns is None else value[:, columns]

    def _write_host(self, key: str, value: torch.Tensor) -> None:
        array = value.numpy()
        target = self._targets.get(key)
        if target is not None:
            target[...] = array
            return
        arrays = self.sim.arrays
        if key == "qf":
            arrays["qfrc_applied"][:, self._dof_sel] = array
            return
        columns, actuators = self._drive_np[key]
        arrays["ctrl"][:, actuators] = array if columns is None else array[:, columns]

    # -- phase 6: the default observation ------------------------------------------------------------
    def observe(self) -> dict[str, torch.Tensor]:
        """``{"qpos", "qvel", "qf"}`` of the active joints, float32 ``(num_envs, n_active)``,
        ``qf`` = actuator + applied joint forces; fresh tensors every call."""
        return self._observe()

    def _observe_host(self) -> dict[str, torch.Tensor]:
        sim = self.sim
        sim.view("qfrc_actuator")  # the read of a derived field runs the lazy forward first
        arrays, dof = sim.arrays, self._dof_sel
        qf = self._qfrc_actuator[:, dof] + arrays["qfrc_applied"][:, dof]
        return {
            "qpos": torch.from_numpy(arrays["qpos"][:, self._qpos_sel].astype(np.float32)),
            "qvel": torch.from_numpy(arrays["qvel"][:, dof].astype(np.float32)),
            "qf": torch.from_numpy(qf.astype(np.float32)),
        }

    def _observe_tensor(self) -> dict[str, torch.Tensor]:
        sim, dof = self.sim, self._dof_idx
        return {
            "qpos": sim.qpos[:, self._qpos_idx].float(),
            "qvel": sim.qvel[:, dof].float(),
            "qf": (sim.qfrc_actuator[:, dof] + sim.qfrc_applied[:, dof]).float(),
        }
