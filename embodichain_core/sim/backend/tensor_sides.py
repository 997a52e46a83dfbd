"""Which tensors a device audit counts as device tensors, host tensors or either.

On Warp's CPU device the simulation's memory and the host's are the same, so
:class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit` tells them apart by where a
tensor came from (see its module docstring). :class:`TensorSides` keeps that bookkeeping:
tensors viewing Warp's arrays, results of ops on device tensors, factories and moves naming
the device are device tensors; a factory or move naming ``torch.device("cpu")`` on a CPU
audit may stand for a host tensor's device as well (``torch.eye(6, device=q.device)``), so
its tensors take *either* side and are never reported as mixing the two.
"""

from __future__ import annotations

import weakref
from typing import Any, Iterator

import numpy as np
import torch

__all__ = ["DEVICE", "EITHER", "HOST", "TensorSides", "flat"]

DEVICE, EITHER, HOST = "device", "either", "host"


class TensorSides:
    """The side of each tensor an audit has seen (a mixin of the audit).

    Args:
        device: the device the audit stands for; a ``torch.device`` equal to it, or any
            ``cuda`` name, is "the device" wherever code names one; the string ``"cpu"``
            names the host.
    """

    def __init__(self, device: Any = "cpu"):
        self.device = torch.device(device)
        self._device: dict[int, weakref.ref] = {}
        self._either: dict[int, weakref.ref] = {}
        self._storages: set[int] = set()

    def mark_device(self, *tensors: Any) -> None:
        """Declare ``tensors`` device tensors (a policy's actions on the GPU, say)."""
        for t in tensors:
            if isinstance(t, torch.Tensor):
                self._device[id(t)] = weakref.ref(t)

    def mark_storage(self, t: Any) -> None:
        """Declare ``t``'s memory device memory: every tensor viewing it is a device tensor
        (Warp's arrays, whatever views and subclasses the backend makes of them)."""
        if isinstance(t, torch.Tensor):
            self._storages.add(t.untyped_storage().data_ptr())

    def is_device(self, t: Any) -> bool:
        """Whether ``t`` is a device tensor (see the module docstring)."""
        if not isinstance(t, torch.Tensor):
            return False
        ref = self._device.get(id(t))
        if ref is not None and ref() is t:
            return True
        return bool(self._storages) and t.untyped_storage().data_ptr() in self._storages

    def _names_device(self, device: Any) -> bool:
        if isinstance(device, str):
            return device.startswith("cuda")
        return isinstance(device, torch.device) and (device == self.device or device.type == "cuda")

    def _target(self, args: tuple, kwargs: dict) -> Any:
        """The device a move/factory call names (``None``: it names none)."""
        if "device" in kwargs:
            return kwargs["device"]
        for a in args:
            if isinstance(a, (str, torch.device)):
                return a
            if isinstance(a, torch.Tensor):
                return self.device if self.is_device(a) else "cpu"
        return None

    def _factory_side(self, device: Any) -> str:
        """A factory naming ``device``: on a CPU audit a ``torch.device`` may be a host
        tensor's (``torch.eye(6, device=q.device)``), so its tensors take either side."""
        if not self._names_device(device):
            return HOST
        return EITHER if isinstance(device, torch.device) and device.type == "cpu" else DEVICE

    def side(self, t: Any) -> str:
        """``"device"``, ``"either"`` (a CPU audit's factory named the device: see
        :meth:`_factory_side`) or ``"host"``."""
        if not self.is_device(t):
            return HOST
        ref = self._either.get(id(t))
        return EITHER if ref is not None and ref() is t else DEVICE

    def _host_tensors(self, values: Any) -> bool:
        """Whether a host tensor that is not a scalar is among ``values``."""
        return any(isinstance(v, torch.Tensor) and v.dim() > 0 and self.side(v) == HOST for v in values)

    def _host_operands(self, values: Iterator[Any]) -> bool:
        """Whether a host tensor (not a scalar), a numpy array or an index list is among them."""
        for v in values:
            if isinstance(v, torch.Tensor) and v.dim() > 0 and not self.is_device(v):
                return True
            if isinstance(v, (np.ndarray, list)) and np.ndim(v) > 0:
                return True
        return False

    def mark_either(self, out: Any) -> None:
        """Declare the tensors of ``out`` (a tensor or a tuple of them) valid on either side."""
        for t in flat((out,)):
            if isinstance(t, torch.Tensor):
                self._device[id(t)] = weakref.ref(t)
                self._either[id(t)] = weakref.ref(t)


def flat(values: Any) -> Iterator[Any]:
    """Tensors and other leaves of (one level of nested) tuples, lists and dicts."""
    for v in values:
        if isinstance(v, (tuple, list)):
            yield from v
        elif isinstance(v, dict):
            yield from v.values()
        else:
            yield v
