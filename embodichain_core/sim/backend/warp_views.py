"""Torch and host views of :class:`~embodichain_core.sim.backend.warp_sim.WarpSim` state.

``wp.to_torch`` turns a MuJoCo Warp array into a zero-copy torch tensor whose vector
dtypes become trailing dims (``xmat`` ``(N, nbody, 3, 3)``); :func:`flat_rows` gives the
shapes ``mujoco.batch`` binds (``(N, nbody, 9)``), still views of the same memory, as a
:class:`CastingView`: item assignment casts float64 (or host) values to the view's float32
on its device, so entities written for the float64 backend write into it unchanged.
:class:`DeviceArrays` stands in for ``sim.arrays`` on CUDA, where no numpy view of
device memory exists: indexing reads a host copy, item assignment writes into the
device tensor.
"""

from __future__ import annotations

from typing import Any, Iterator, Mapping

import numpy as np
import torch


class CastingView(torch.Tensor):
    """A tensor (same storage) whose item assignment converts the values' dtype and device;
    every other operation returns plain tensors (torch functions are not overridden)."""

    __torch_function__ = torch._C._disabled_torch_function_impl  # type: ignore[assignment]

    def __setitem__(self, key: Any, value: Any) -> None:
        if isinstance(value, torch.Tensor) and (value.dtype != self.dtype or value.device != self.device):
            value = value.to(device=self.device, dtype=self.dtype)
        super().__setitem__(key, value)


def flat_rows(view: torch.Tensor, num_envs: int) -> torch.Tensor:
    """``view`` with 3x3 matrices flattened to 9 (as ``mujoco.batch`` binds them), as a
    :class:`CastingView` of the same memory."""
    if view.dim() == 4 and view.shape[-2:] == (3, 3):
        view = view.view(num_envs, view.shape[1], 9)
    return view.as_subclass(CastingView)


def _index(key: Any, device: torch.device) -> Any:
    if isinstance(key, tuple):
        return tuple(_index(k, device) for k in key)
    if isinstance(key, np.ndarray):
        return torch.as_tensor(key, device=device)
    return key


class DeviceArray:
    """Numpy-like access to one device tensor: ``a[idx]`` copies to the host, ``a[idx] = v``
    writes the device tensor (numpy index arrays allowed)."""

    def __init__(self, tensor: torch.Tensor):
        self.tensor = tensor

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.tensor.shape)

    def __getitem__(self, key: Any) -> np.ndarray:
        return self.tensor[_index(key, self.tensor.device)].detach().cpu().numpy()

    def __setitem__(self, key: Any, values: Any) -> None:
        values = values.detach() if isinstance(values, torch.Tensor) else np.asarray(values)
        self.tensor[_index(key, self.tensor.device)] = torch.as_tensor(
            values, dtype=self.tensor.dtype, device=self.tensor.device
        )

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        out = self.tensor.detach().cpu().numpy()
        return out if dtype is None else out.astype(dtype)


class DeviceArrays(Mapping[str, DeviceArray]):
    """``sim.arrays`` of a CUDA backend: a :class:`DeviceArray` per state field."""

    def __init__(self, tensors: Mapping[str, torch.Tensor]):
        self._arrays = {name: DeviceArray(t) for name, t in tensors.items()}

    def __getitem__(self, name: str) -> DeviceArray:
        return self._arrays[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._arrays)

    def __len__(self) -> int:
        return len(self._arrays)
