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
  envs, the value and the bounds. The bounds apply to array actions of the action space's
  width, on every device.

The result is a float32 tensor ``(num_envs, width)`` (a dict of them for dict actions).
"""

from __future__ import annotations

from typing import Any, Mapping, Optional, Sequence

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
        self.strict, self.out_of_space = bool(strict), 0
        self._box = _box_bounds(space, self.widths[0])
        self._limits: dict[tuple[int, bool, torch.device], tuple[torch.Tensor, torch.Tensor]] = {}

    def __call__(self, action: Any) -> torch.Tensor | dict[str, torch.Tensor]:
        if (
            type(action) is torch.Tensor
            and action.dtype is torch.float32
            and action.shape in self._shapes
            and action.layout is torch.strided
        ):  # the common case: checked, not converted
            self._check_device(action, "action")
            self._check_values(action.detach(), "action")
            return action
        if isinstance(action, Mapping):
            return self._check_dict(action)
        return self._check_array(action, self.widths, "action")

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
        self._check_values(tensor.detach(), what)
        return tensor

    def _check_values(self, tensor: torch.Tensor, what: str) -> None:
        """NaN and infinite values raise; values outside the action space are counted (or
        raise with ``strict``). The common case is decided by one clamp: to the bounds, or
        to the largest finite float where there are none, so that only an action with a
        value outside, NaN or infinite differs from its clamped copy."""
        low, high = self._bounds_of(tensor, what)
        if torch.equal(tensor.clamp(low, high), tensor):
            return
        finite = torch.isfinite(tensor).all(dim=-1)
        if not bool(finite.all()):
            bad = torch.nonzero(~finite).flatten().tolist()
            raise ValueError(f"{what} has NaN or infinite values in env(s) {bad[:8]}")
        outside = (tensor < low) | (tensor > high)
        rows = outside.any(dim=-1)
        if self.strict:
            env, dim = (int(i) for i in torch.nonzero(outside)[0])
            raise ValueError(
                f"action outside the action space in env(s) {torch.nonzero(rows).flatten()[:8].tolist()}: value "
                f"{float(tensor[env, dim]):g} at index {dim} is not in [{float(low[dim]):g}, {float(high[dim]):g}] "
                f"(action space {self.space}; strict action check: without it the value would be clipped)"
            )
        self.out_of_space += int(rows.sum())

    def _bounds_of(self, tensor: torch.Tensor, what: str) -> tuple[torch.Tensor, torch.Tensor]:
        """``(low, high)`` of one env's values on the tensor's device: the action space's
        bounds for an action of its width, else none; the largest finite float32 stands
        for an infinite bound."""
        width = int(tensor.shape[-1])
        bounded = what == "action" and self._box is not None and width == self.widths[0]
        key = (width, bounded, tensor.device)
        limits = self._limits.get(key)
        if limits is None:
            big = np.finfo(np.float32).max
            low, high = self._box if bounded and self._box is not None else (np.full(width, -big), np.full(width, big))
            low, high = (np.clip(x, -big, big).astype(np.float32) for x in (low, high))
            limits = (torch.as_tensor(low, device=tensor.device), torch.as_tensor(high, device=tensor.device))
            self._limits[key] = limits
        return limits

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

    def _expected(self, widths: Sequence[int]) -> str:
        alt = f" or {widths[1:]} values per env" if len(widths) > 1 else ""
        return f"shape ({self.num_envs}, {widths[0]}){alt}"


def _box_bounds(space: Any, width: int) -> Optional[tuple[np.ndarray, np.ndarray]]:
    """``(low, high)`` of one env's action (a Box of ``width`` values, batched or not),
    ``None`` when the space has no such bounds or is unbounded everywhere."""
    low, high = getattr(space, "low", None), getattr(space, "high", None)
    if low is None or high is None:
        return None
    low, high = np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32)
    if low.ndim == 2:
        low, high = low[0], high[0]
    if low.shape != (width,) or high.shape != (width,) or not (np.isfinite(low).any() or np.isfinite(high).any()):
        return None
    return low, high
