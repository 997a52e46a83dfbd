"""Helpers of the batched IK: one torch thread for tiny tensors, joint sampling, rotation errors."""

from __future__ import annotations

import contextlib
import functools
from typing import Any, Callable, Iterator, Optional, TypeVar

import torch

_F64 = torch.float64
_T = TypeVar("_T", bound=Callable[..., Any])


@contextlib.contextmanager
def single_threaded() -> Iterator[None]:
    """Run torch ops on one thread: the solver's tensors are tiny, and intra-op
    threads make them up to 10x slower on a busy 2-core machine (measured)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def one_thread(func: _T) -> _T:
    """``func`` run inside :func:`single_threaded`."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with single_threaded():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def sample_joint_values(limits: torch.Tensor, n: int, generator: Optional[torch.Generator] = None) -> torch.Tensor:
    """(n, k) float64 joint values drawn uniformly inside (k, 2) ``limits`` (clipped to +-pi)."""
    lo = limits[:, 0].to(_F64).clamp(min=-torch.pi)
    hi = limits[:, 1].to(_F64).clamp(max=torch.pi)
    return lo + (hi - lo) * torch.rand(n, len(lo), generator=generator, dtype=_F64)


def rotation_error(target: torch.Tensor, rot: torch.Tensor) -> torch.Tensor:
    """(N, 3) orientation error vector ``0.5 * sum_k rot_k x target_k`` (root frame)."""
    return 0.5 * torch.linalg.cross(rot, target, dim=-2).sum(-1)


def rotation_angle(target: torch.Tensor, rot: torch.Tensor) -> torch.Tensor:
    """(N,) angle of ``target @ rot^T`` in radians (exact, for success checks)."""
    cos = ((target * rot).sum((-1, -2)) - 1.0) / 2.0
    return torch.arccos(cos.clamp(-1.0, 1.0))
