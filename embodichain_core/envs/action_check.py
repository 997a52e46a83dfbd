"""The action check at the env boundary: one clear error for a bad action, before any term.

The rule (docs/embodied_env.md, "Actions"):

* A tensor, numpy array, list/tuple of numbers or a Python number, of a real dtype
  (floats, or integers, which are converted); ``bool``, complex, strings, ``None``
  and other objects are a ``TypeError``.
* Shape ``(num_envs, action_dim)``. A 1-D action of ``action_dim`` values is the same
  action for every env; with ``action_dim == 1`` a 1-D action of ``num_envs`` values
  and a scalar are accepted too. Any other shape is a ``ValueError`` naming the
  expected shape and the action space.
* A tensor on another device than the env's is a ``ValueError`` (no silent copies
  between devices). NaN or infinite values are a ``ValueError`` naming the envs.
* A dict action (for dict-driven action terms, or ``qpos``/``qvel``/``qf`` commands
  without action terms) must use the known keys; each value follows the rule above
  with its own width.
* A sparse (or otherwise non-strided) tensor is a ``TypeError`` asking for ``to_dense()``.
* Values outside the action space (a ``Box``'s ``low``/``high``) are accepted and left to
  the action terms and drives, which clip them (``DeltaQposTerm`` clips its targets to the
  joint limits, the drives their forces); :attr:`ActionChecker.out_of_space` counts the
  env-steps that had one. With ``strict`` such an action is a ``ValueError`` naming the
  envs, the value and the bounds. The bounds are checked for array actions of the action
  space's width on the CPU (a GPU action only with ``strict``).

The result is a float32 tensor ``(num_envs, width)`` (a dict of them for dict actions).
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import torch

__all__ = ["ActionChecker"]

_REAL = (
    torch.float32,
    torch.float64,
    torch.float16,
    torch.bfloat16,
    torch.int8,
    torch.int16,
    torch.int32,
    torch.int64,
    torch.uint8,
)


class ActionChecker:
    """Checks and normalizes actions for an env of ``num_envs`` envs.

    Args:
        num_envs: the batch size.
        widths: accepted numbers of values per env (the first is the action space's).
        device: the env's device.
        space: the action space, shown in messages.
        dict_widths: accepted dict keys -> their accepted widths (empty: dicts rejected).
        detail: what the values mean, appended to shape errors (e.g. the terms' split).
        strict: an action outside the action space's bounds raises instead of being counted.

    Attributes:
        out_of_space: env-steps whose action had a value outside the action space (clipped
            downstream; see the module docstring).
    """

    def __init__(
        self,
        num_envs: int,
        widths: Sequence[int],
        device: torch.device,
        space: Any,
        dict_widths: Mapping[str, Sequence[int]] | None = None,
        detail: str = "",
        strict: bool = False,
    ):
        self.num_envs, self.widths = int(num_envs), [int(w) for w in widths]
        self.device, self.detail = torch.device(device), detail
        shape, dtype = getattr(space, "shape", None), getattr(space, "dtype", None)
        self.space = f"{type(space).__name__}(shape={shape}, dtype={dtype})" if shape is not None else str(space)
        self.dict_widths = {k: [int(w) for w in v] for k, v in (dict_widths or {}).items()}
        self._shapes = frozenset((self.num_envs, w) for w in self.widths)  # taken as they are
        self._on_cpu = self.device.type == "cpu"
        self._last: tuple[Any, Any] = (None, None)  # (the last CPU action passed as is, its numpy view)
        self.strict, self.out_of_space = bool(strict), 0
        self._bounds = _box_bounds(space, self.widths[0])

    def __call__(self, action: Any) -> torch.Tensor | dict[str, torch.Tensor]:
        if (
            type(action) is torch.Tensor
            and action.dtype is torch.float32
            and action.shape in self._shapes
            and action.layout is torch.strided
        ):
            # the common case: no conversion at all; on the CPU one numpy check
            if self._on_cpu and action.is_cpu and not action.requires_grad:
                array = action.numpy()
                if np.count_nonzero(np.isfinite(array)) == array.size:  # ~0.5 us; .all() takes ~1 us
                    self._check_bounds(array)
                    self._last = (action, array)
                    return action
            self._last = (None, None)
            self._check_device(action, "action")
            self._check_finite(action, "action")
            self._check_bounds_tensor(action)
            return action
        self._last = (None, None)
        if isinstance(action, Mapping):
            return self._check_dict(action)
        return self._check_array(action, self.widths, "action")

    def host_array(self, tensor: Any) -> np.ndarray | None:
        """The numpy view of ``tensor`` if it is the CPU action the last call returned as it
        was (the command write then needs no second ``Tensor.numpy()``), else ``None``."""
        last, array = self._last
        return array if tensor is last else None

    def _check_dict(self, action: Mapping) -> dict[str, torch.Tensor]:
        if not self.dict_widths:
            raise TypeError(
                f"this env takes an array action of shape {self._expected(self.widths)} "
                f"(action space {self.space}), got a dict with keys {list(action)}"
            )
        unknown = [k for k in action if k not in self.dict_widths]
        if unknown or not action:
            raise ValueError(
                f"action dict keys {list(action)}: expected some of {list(self.dict_widths)} (unknown: {unknown})"
            )
        return {
            key: self._check_array(value, self.dict_widths[key], f"action[{key!r}]") for key, value in action.items()
        }

    def _check_array(self, value: Any, widths: Sequence[int], what: str) -> torch.Tensor:
        tensor = self._as_tensor(value, widths, what)
        self._check_device(tensor, what)
        tensor = self._shaped(tensor, widths, what).to(torch.float32)
        self._check_finite(tensor, what)
        if what == "action":
            self._check_bounds_tensor(tensor)
        return tensor

    def _check_bounds_tensor(self, tensor: torch.Tensor) -> None:
        if tensor.device.type == "cpu":
            self._check_bounds(tensor.detach().numpy())
        elif self.strict and self._bounds is not None and tensor.shape[-1] == self._bounds[0].shape[0]:
            self._check_bounds(tensor.detach().cpu().numpy())

    def _check_bounds(self, array: np.ndarray) -> None:
        """Count (or with ``strict`` raise for) the envs whose action leaves the space."""
        if self._bounds is None:
            return
        low, high, uniform = self._bounds
        if array.shape[-1] != low.shape[0]:
            return
        if uniform and low[0] <= array.min() and array.max() <= high[0]:  # the common case: two reductions
            return
        outside = ((array < low) | (array > high)).reshape(-1, low.shape[0])
        rows = outside.any(axis=-1)
        count = int(np.count_nonzero(rows))
        if not count:
            return
        if self.strict:
            env, dim = (int(i) for i in np.argwhere(outside)[0])
            value = float(array.reshape(-1, low.shape[0])[env, dim])
            raise ValueError(
                f"action outside the action space in env(s) {np.flatnonzero(rows)[:8].tolist()}: value {value:g} "
                f"at index {dim} is not in [{low[dim]:g}, {high[dim]:g}] (action space {self.space}; strict "
                "action check: without it the value would be clipped)"
            )
        self.out_of_space += count

    def _as_tensor(self, value: Any, widths: Sequence[int], what: str) -> torch.Tensor:
        expected = f"expected {self._expected(widths)} (action space {self.space})"
        if value is None or isinstance(value, (str, bytes)):
            raise TypeError(f"{what} is {type(value).__name__}; {expected}")
        if isinstance(value, torch.Tensor):
            if value.layout != torch.strided:
                raise TypeError(f"{what} is a {value.layout} tensor; {expected} as a dense tensor (use .to_dense())")
            tensor = value
        else:
            try:
                array = np.asarray(value)
            except (ValueError, TypeError) as err:  # ragged lists
                raise TypeError(f"{what} cannot be read as a numeric array ({err}); {expected}") from None
            if array.dtype.kind not in "fiu":
                raise TypeError(f"{what} has dtype {array.dtype}; {expected} of real numbers")
            tensor = torch.from_numpy(np.ascontiguousarray(array))
        if tensor.dtype not in _REAL:
            raise TypeError(f"{what} has dtype {tensor.dtype}; {expected} of real numbers")
        return tensor

    def _shaped(self, tensor: torch.Tensor, widths: Sequence[int], what: str) -> torch.Tensor:
        n, shape = self.num_envs, tuple(tensor.shape)
        if len(shape) == 2 and shape[0] == n and shape[1] in widths:
            return tensor
        if len(shape) == 1 and shape[0] in widths:
            return tensor.unsqueeze(0).expand(n, -1)
        if 1 in widths and (shape == () or shape == (n,)):
            return tensor.reshape(-1, 1).expand(n, 1)
        detail = f"; {self.detail}" if self.detail and what == "action" else ""
        raise ValueError(
            f"{what} has shape {shape}; expected {self._expected(widths)} (action space "
            f"{self.space}; a 1-D action of {widths[0]} values is applied to every env){detail}"
        )

    def _check_device(self, tensor: torch.Tensor, what: str) -> None:
        if tensor.device.type != self.device.type:
            raise ValueError(
                f"{what} is on device {tensor.device}; the env runs on {self.device} "
                f"(move it with .to({str(self.device)!r}))"
            )

    @staticmethod
    def _check_finite(tensor: torch.Tensor, what: str) -> None:
        if tensor.device.type == "cpu" and tensor.dtype is torch.float32:
            if np.isfinite(tensor.detach().numpy()).all():  # numpy: ~1 us where torch takes ~6 us
                return
        finite = torch.isfinite(tensor).all(dim=-1)
        if not bool(finite.all()):
            bad = torch.nonzero(~finite).flatten().tolist()
            raise ValueError(f"{what} has NaN or infinite values in env(s) {bad[:8]}")

    def _expected(self, widths: Sequence[int]) -> str:
        alt = f" or {widths[1:]} values per env" if len(widths) > 1 else ""
        return f"shape ({self.num_envs}, {widths[0]}){alt}"


def _box_bounds(space: Any, width: int) -> tuple[np.ndarray, np.ndarray, bool] | None:
    """``(low, high, uniform)`` of one env's action (a Box of ``width`` values, batched or
    not), ``None`` when the space has no such bounds or is unbounded everywhere."""
    low, high = getattr(space, "low", None), getattr(space, "high", None)
    if low is None or high is None:
        return None
    low, high = np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32)
    if low.ndim == 2:
        low, high = low[0], high[0]
    if low.shape != (width,) or high.shape != (width,) or not (np.isfinite(low).any() or np.isfinite(high).any()):
        return None
    uniform = bool((low == low[0]).all() and (high == high[0]).all())
    return low, high, uniform
