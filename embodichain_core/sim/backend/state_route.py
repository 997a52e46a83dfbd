"""How entities read and write simulation state: one route per consumer, chosen once.

A backend whose state lives in host memory (``sim.capabilities.host_arrays``:
``mujoco_batch``, and ``warp`` on Warp's CPU device by default) offers numpy views of it
(``sim.arrays``); indexing those costs about a microsecond, a torch index about four. Any
other backend (``warp`` on a GPU) keeps its state in device memory, reached only through
its torch views (``sim.tensors`` and ``sim.<field>``). :func:`state_route` picks the
matching route once, when an entity binds to the simulation; the entity then calls the
route and never asks again which memory it has.

Both routes take the same arguments and give the same values:

* an ``index`` is a tuple of ints, slices, int64 numpy arrays or long tensors, as numpy
  or torch index a ``(num_envs, ...)`` field (``(rows[:, None], cols[None, :])``);
* :meth:`StateRoute.write` takes numbers, numpy arrays or tensors of any float dtype and
  converts them explicitly to the field's dtype (float64 on ``mujoco_batch``, float32 on
  ``warp``) and memory;
* :meth:`StateRoute.read` returns host numpy values in the field's dtype (a copy on the
  device route; a view for basic indexing on the host route);
* :meth:`StateRoute.rows` and :meth:`StateRoute.pose` return float32 tensors on the
  consumer's device, fresh on the host route.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.sim.backend.interface import STATE_FIELDS

_STATE = frozenset(STATE_FIELDS)


class StateRoute:
    """Reads and writes of a backend's state fields for one consumer (an entity).

    Args:
        sim: the simulation backend.
        device: where reads are returned (the env's device).

    Attributes:
        host: whether this is the numpy route (:class:`HostRoute`).
    """

    host: bool = False

    def __init__(self, sim: Any, device: torch.device):
        self.sim = sim
        self.device = torch.device(device)

    def read(self, name: str, index: Any) -> np.ndarray:
        """Host numpy values ``field[index]`` in the field's dtype."""
        raise NotImplementedError

    def write(self, name: str, index: Any, values: Any) -> None:
        """``field[index] = values``, converted to the field's dtype and memory (a state field)."""
        raise NotImplementedError

    def rows(self, name: str, index: Any) -> torch.Tensor:
        """``field[index]`` as float32 on :attr:`device` (state or derived field)."""
        raise NotImplementedError

    def pose(self, pos: str, quat: str, index: Any) -> torch.Tensor:
        """``(n, 7)`` float32 poses on :attr:`device`: ``pos[index]`` (n, 3) then ``quat[index]`` (n, 4)."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(device={self.device})"


class HostRoute(StateRoute):
    """Through the backend's numpy views (``sim.arrays``; derived fields as numpy views of
    their tensors, read through ``sim.view`` so that the lazy forward runs first)."""

    host = True

    def __init__(self, sim: Any, device: torch.device):
        super().__init__(sim, device)
        self.arrays = sim.arrays
        self._on_cpu = self.device.type == "cpu"

    def _array(self, name: str) -> np.ndarray:
        return self.arrays[name] if name in _STATE else self.sim.view(name).numpy()

    def read(self, name: str, index: Any) -> np.ndarray:
        return self._array(name)[_host_index(index)]

    def write(self, name: str, index: Any, values: Any) -> None:
        if isinstance(values, torch.Tensor):
            values = values.detach().cpu().numpy()
        self.arrays[name][_host_index(index)] = values

    def _out(self, values: np.ndarray) -> torch.Tensor:
        out = torch.from_numpy(np.asarray(values, dtype=np.float32))
        return out if self._on_cpu else out.to(self.device)

    def rows(self, name: str, index: Any) -> torch.Tensor:
        values = self._array(name)[_host_index(index)]
        return self._out(values if values.dtype != np.float32 else values.copy())

    def pose(self, pos: str, quat: str, index: Any) -> torch.Tensor:
        index = _host_index(index)
        p, q = self._array(pos)[index], self._array(quat)[index]
        out = np.empty((len(p), 7), dtype=np.float32)
        out[:, :3] = p
        out[:, 3:] = q
        return self._out(out)


class DeviceRoute(StateRoute):
    """Through the backend's torch views (``sim.tensors``; derived fields through
    ``sim.view``): index arrays and values are moved to the sim's device and values cast
    to the view's dtype before they are written."""

    def __init__(self, sim: Any, device: torch.device):
        super().__init__(sim, device)
        self.tensors = sim.tensors
        self._sim_device = torch.device(sim.device)

    def _view(self, name: str) -> torch.Tensor:
        return self.tensors[name] if name in _STATE else self.sim.view(name)

    def _index(self, index: Any) -> Any:
        keys = index if isinstance(index, tuple) else (index,)
        return tuple(
            torch.as_tensor(k, device=self._sim_device) if isinstance(k, (np.ndarray, torch.Tensor)) else k
            for k in keys
        )

    def read(self, name: str, index: Any) -> np.ndarray:
        return self._view(name)[self._index(index)].detach().cpu().numpy()

    def write(self, name: str, index: Any, values: Any) -> None:
        view = self._view(name)
        if isinstance(values, torch.Tensor):
            values = values.detach()
        elif isinstance(values, np.ndarray) and not values.flags.writeable:
            values = np.ascontiguousarray(values)  # a broadcast array: torch wants its own memory
        view[self._index(index)] = torch.as_tensor(values, dtype=view.dtype, device=view.device)

    def rows(self, name: str, index: Any) -> torch.Tensor:
        return self._view(name)[self._index(index)].to(dtype=torch.float32, device=self.device)

    def pose(self, pos: str, quat: str, index: Any) -> torch.Tensor:
        index = self._index(index)
        out = torch.cat((self._view(pos)[index], self._view(quat)[index]), dim=-1)
        return out.to(dtype=torch.float32, device=self.device)


def _host_index(index: Any) -> Any:
    """``index`` with torch index tensors as numpy arrays (``index`` itself when it has none:
    the entities' cached numpy indices, on every read of the step)."""
    if isinstance(index, torch.Tensor):
        return index.numpy()
    if isinstance(index, tuple):
        for k in index:
            if isinstance(k, torch.Tensor):
                return tuple(k.numpy() if isinstance(k, torch.Tensor) else k for k in index)
    return index


def state_route(sim: Any, device: Any) -> StateRoute:
    """The route to ``sim``'s state for a consumer whose outputs live on ``device``: numpy
    views where the backend has them (``sim.capabilities.host_arrays``), else its torch views.

    Args:
        sim: the simulation backend.
        device: the consumer's device (the env's device; reads are returned there).
    """
    return (HostRoute if sim.capabilities.host_arrays else DeviceRoute)(sim, torch.device(device))
