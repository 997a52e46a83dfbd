"""Torch views of :class:`~embodichain_core.sim.backend.warp_sim.WarpSim` state.

``wp.to_torch`` turns a MuJoCo Warp array into a zero-copy torch tensor whose vector
dtypes become trailing dims (``xmat`` ``(N, nbody, 3, 3)``); :func:`flat_rows` gives the
shapes ``mujoco.batch`` binds (``(N, nbody, 9)``), still views of the same memory. They
are plain float32 tensors: code that writes float64 values into them converts first (the
entities do, through :mod:`~embodichain_core.sim.backend.state_route`).
"""

from __future__ import annotations

import torch


def flat_rows(view: torch.Tensor, num_envs: int) -> torch.Tensor:
    """``view`` with 3x3 matrices flattened to 9 (as ``mujoco.batch`` binds them), a view of
    the same memory."""
    if view.dim() == 4 and view.shape[-2:] == (3, 3):
        view = view.view(num_envs, view.shape[1], 9)
    return view
