"""Device audit: count, on any device, the calls that would make the host wait for a GPU.

On a CUDA device every read of device memory by the host (``.item()``, ``.tolist()``,
``.cpu()``, ``.numpy()``, ``bool(tensor)``, ``nonzero``, indexing with a boolean mask) waits
until the queued kernels finish, and so does every blocking copy of host data into an op
on the device (an index list, a numpy array, a CPU tensor). :class:`HostWaitAudit` counts
those calls by call site while a block runs, so a test on Warp's CPU device catches a wait
that would stall the GPU. It also lists the ops that mix device tensors with host tensors
(other than scalars and explicit copies): on the CPU they run, on CUDA they raise.

It tells device tensors from host tensors by where they came from, since on the CPU both
live in the same memory: Warp's arrays as torch tensors (``wp.to_torch``: the simulation's
views) are device tensors, and so is the result of any op on a device tensor, of a factory
given a ``torch.device`` (``torch.zeros(n, device=env.device)``) and of ``.to(env.device)``;
every other tensor is a host tensor, and the string ``"cpu"`` (``.to("cpu")``) names the
host. So the audit spans the env's build, and an env built inside it takes its device code
paths: the audit enters :func:`~embodichain_core.sim.backend.warp_device.cpu_device_route`,
so backend ``warp`` on Warp's CPU device has no host arrays there and the entities and the
robot commands use the torch views, as on a GPU (:meth:`HostWaitAudit.check_env` refuses an
env whose backend offers host arrays).

Example:
    >>> with HostWaitAudit("cpu") as audit:  # doctest: +SKIP
    ...     env = gym.make("PushCube-v1", cfg=cfg, num_envs=2).unwrapped
    ...     action = torch.zeros(env.action_space.shape, device=env.device)
    ...     env.reset(seed=0)
    ...     audit.clear()
    ...     for _ in range(10):
    ...         env.step(action)
    >>> audit.per_step(10)["per_step"]  # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import functools
import re
import traceback
from collections import Counter
from typing import Any, Callable

import numpy as np
import torch
from torch.overrides import TorchFunctionMode

from embodichain_core.sim.backend.tensor_sides import DEVICE, EITHER, HOST, TensorSides, flat
from embodichain_core.sim.backend.warp_device import cpu_device_route

#: Reads of device memory by the host.
_READS = {
    torch.Tensor.item: "item",
    torch.Tensor.tolist: "tolist",
    torch.Tensor.__bool__: "bool",
    torch.Tensor.__int__: "int",
    torch.Tensor.__float__: "float",
    torch.Tensor.__index__: "index",
    torch.Tensor.numpy: "numpy",
    torch.Tensor.__array__: "numpy",
    torch.Tensor.cpu: "cpu",
    torch.Tensor.nonzero: "nonzero",
    torch.nonzero: "nonzero",
    torch.argwhere: "nonzero",
    torch.masked_select: "masked_select",
    torch.Tensor.masked_select: "masked_select",
    torch.unique: "unique",
    torch.Tensor.unique: "unique",
}
_INDEXING = {torch.Tensor.__getitem__, torch.Tensor.__setitem__}
_MOVES = {torch.Tensor.to, torch.as_tensor, torch.tensor, torch.Tensor.new_tensor}
#: Explicit copies: a host source is a blocking host-to-device copy, not an error.
_COPIES = {torch.Tensor.copy_}
#: The kind of an op mixing device tensors with host tensors (not scalars): CUDA raises there.
MIXED = "mixed_devices"
_WARP_WAITS = ("synchronize", "synchronize_device", "synchronize_stream", "synchronize_event")
_PROJECT = re.compile(r"(embodichain_\w+)/(.+\.py)$")


def call_site(depth: int = 3) -> str:
    """The innermost frames (up to ``depth``) of the project's code on the current stack,
    ``path:line  code <- caller <- ...``."""
    sites: list[str] = []
    for frame in reversed(traceback.extract_stack()[:-2]):
        match = _PROJECT.search(frame.filename.replace("\\", "/"))
        if match is None or frame.filename.endswith("device_audit.py"):
            continue
        where = f"{match.group(1)}/{match.group(2)}:{frame.lineno}"
        sites.append(where + ("" if sites else f"  {(frame.line or '').strip()}"))
        if len(sites) == depth:
            break
    return " <- ".join(sites) if sites else "(outside the project)"


class HostWaitAudit(TensorSides, TorchFunctionMode):
    """Count host waits (device-to-host reads, blocking host-to-device copies) by call site.

    Enter it before the env is built, so that the tensors the env makes on its device at
    build and reset are known as device tensors (and that backend ``warp`` on Warp's CPU
    device is built without host arrays, taking a GPU's code paths), and call :meth:`clear`
    before the block to measure.

    Args:
        device: the device the audit stands for (the env's ``sim_device``; ``"cpu"`` for
            Warp's CPU device). A ``torch.device`` equal to it, or any ``cuda`` name, is
            "the device" wherever code names one; the string ``"cpu"`` names the host.
    """

    def __init__(self, device: Any = "cpu"):
        TorchFunctionMode.__init__(self)
        TensorSides.__init__(self, device)
        self.waits: Counter[tuple[str, str]] = Counter()
        self._undo: list[Callable[[], None]] = []

    @staticmethod
    def check_env(env: Any) -> None:
        """Raise ``ValueError`` when ``env``'s backend exposes host views of its state
        (``capabilities.host_arrays``): the env then takes host code paths a GPU never runs."""
        sim = getattr(env, "unwrapped", env).sim
        if sim.capabilities.host_arrays:
            raise ValueError(
                "HostWaitAudit: the backend exposes host views (capabilities.host_arrays); build the env "
                "(backend 'warp') inside the audit's with-block so that it takes its device paths"
            )

    def clear(self) -> None:
        """Forget the waits counted so far (the device tensors stay known)."""
        self.waits.clear()

    # -- counting ------------------------------------------------------------------------------------
    def record(self, kind: str) -> None:
        """Count one wait of ``kind`` at the current project call site."""
        self.waits[(kind, call_site())] += 1

    def _classify(self, func: Any, args: tuple, kwargs: dict) -> tuple[str | None, str]:
        """``(wait kind or None, the side of the result: device, either or host)``."""
        sides = [(self.side(a), a.dim()) for a in (*flat(args), *flat(kwargs.values())) if isinstance(a, torch.Tensor)]
        on_device = any(side != HOST for side, _ in sides)
        if func in _MOVES:
            return self._move(func, args, kwargs, on_device, sides)
        if "device" in kwargs:  # a factory: zeros(..., device=sim.device)
            return None, self._factory_side(kwargs["device"])
        if func in _INDEXING:
            return self._indexing(func, args)
        if not on_device:
            return None, HOST
        if func in _READS:
            return _READS[func], HOST
        certain = any(side == DEVICE for side, _ in sides)
        host = any(side == HOST and dim > 0 for side, dim in sides)
        if func in _COPIES:
            return ("to_device" if self.side(args[1]) == HOST else None), self.side(args[0])
        if certain and host:
            return MIXED, DEVICE  # CUDA raises: expected all tensors to be on the same device
        return None, DEVICE if certain else (HOST if host else EITHER)

    def _move(self, func: Any, args: tuple, kwargs: dict, on_device: bool, sides: list) -> tuple[str | None, str]:
        """A ``.to()`` / ``as_tensor`` / ``tensor``: a copy to the host or to the device, or none."""
        target = self._target(args[1:] if func is torch.Tensor.to else (), kwargs)
        if target is None:
            return None, sides[0][0] if sides else HOST
        to_device = self._names_device(target)
        if on_device and not to_device:
            return "to_host", HOST
        if to_device and not on_device:
            return "to_device", self._factory_side(target)
        return None, sides[0][0] if sides else HOST

    def _indexing(self, func: Any, args: tuple) -> tuple[str | None, str]:
        """The wait kind of ``t[key]`` / ``t[key] = value``, and the side of the result."""
        base, key = self.side(args[0]), args[1]
        keys = key if isinstance(key, tuple) else (key,)
        value = args[2:] if func is torch.Tensor.__setitem__ else ()
        advanced = any(isinstance(k, (torch.Tensor, np.ndarray, list)) for k in keys)
        if base == HOST:
            device_keys = any(self.side(k) == DEVICE for k in flat(keys))
            device_value = any(self.side(v) == DEVICE and v.dim() > 0 for v in value)
            if device_keys or (device_value and advanced):
                return MIXED, HOST  # device indices into host memory, or index_put_ of device values
            return ("to_host" if device_value else None), HOST
        if any(isinstance(k, torch.Tensor) and k.dtype == torch.bool for k in keys):
            return "bool_mask", base
        if advanced and base == DEVICE and self._host_tensors(value):
            return MIXED, base  # index_put_ of host values into device memory
        if self._host_operands(flat(args[1:])):
            return "host_index", base
        return None, base

    def __torch_function__(self, func: Any, types: Any, args: tuple = (), kwargs: Any = None) -> Any:
        kwargs = kwargs or {}
        kind, side = self._classify(func, args, kwargs)
        if kind is not None:
            self.record(kind)
        out = func(*args, **kwargs)
        if kind in ("cpu", "to_host", "to_device") and any(out is a for a in args):
            out = out.clone()  # on the CPU a move returns its input: keep the copy apart
        if side == EITHER:
            self.mark_either(out)
        elif side == DEVICE:
            self.mark_device(*flat((out,)))
        return out

    # -- Warp ----------------------------------------------------------------------------------------
    def _patch_warp(self) -> None:
        try:
            import warp as wp
        except ImportError:
            return
        for name in _WARP_WAITS:
            self._wrap(wp, name, functools.partial(self._record_after, f"warp.{name}"))
        self._wrap(wp.array, "numpy", functools.partial(self._record_after, "warp.numpy"))
        self._wrap(wp, "to_torch", self.mark_storage)

    def _record_after(self, kind: str, out: Any) -> None:
        self.record(kind)

    def _wrap(self, owner: Any, name: str, after: Callable[[Any], None]) -> None:
        original = getattr(owner, name, None)
        if original is None:
            return

        def wrapped(*args: Any, **kwargs: Any) -> Any:
            out = original(*args, **kwargs)
            after(out)
            return out

        setattr(owner, name, wrapped)
        self._undo.append(lambda: setattr(owner, name, original))

    def __enter__(self) -> "HostWaitAudit":
        from embodichain_core.utils import math as math_utils

        was, consts = math_utils.NUMPY_VIEWS, dict(math_utils._CONSTS)
        math_utils.NUMPY_VIEWS = False  # the torch code a GPU runs, not the CPU's numpy fast path
        math_utils._CONSTS.clear()  # per-device constants made before would be host tensors here
        self._undo.append(lambda: setattr(math_utils, "NUMPY_VIEWS", was))
        self._undo.append(lambda: math_utils._CONSTS.update(consts))
        route = contextlib.ExitStack()
        route.enter_context(cpu_device_route())  # envs built inside take a GPU's code paths
        self._undo.append(route.close)
        self._patch_warp()
        super().__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        super().__exit__(*exc)
        while self._undo:
            self._undo.pop()()

    def per_step(self, steps: int) -> dict[str, Any]:
        """Waits per step in all, by kind, and by call site (most frequent first); the ops that
        mix device and host tensors (errors on CUDA, not waits) apart, under ``"mixed"``."""
        kinds: Counter[str] = Counter()
        for (kind, _), n in self.waits.items():
            if kind != MIXED:
                kinds[kind] += n
        counted = self.waits.most_common()
        return {
            "per_step": sum(kinds.values()) / steps,
            "by_kind": {k: n / steps for k, n in kinds.most_common()},
            "sites": [{"kind": k, "site": s, "per_step": n / steps} for (k, s), n in counted if k != MIXED],
            "mixed": [{"site": s, "count": n} for (k, s), n in counted if k == MIXED],
        }
