"""Where :meth:`Robot.compute_ik <embodichain_core.sim.entities.robot.Robot.compute_ik>` solves.

On the host route (``mujoco_batch``, and ``warp`` with host views) the solver's ``get_ik``
runs on the CPU, as it always has. On the device route (``warp`` on a GPU) a solver with
``ik_on_device`` first solves every env where the state is, with no host read
(``get_ik_on_device``: the DLS iterations of ``get_ik``'s first attempt); one read then finds
the envs it left unsolved, and only those go to ``get_ik`` on the CPU for its random
restarts. Where the first attempt converges both routes give the same joint values, and
the restarts depend on the target alone, so the result is ``get_ik``'s either way: the
scripted demonstrations of a GPU run plan as on the CPU, with one wait per solve.

Example:
    >>> success, qpos = solve_part_ik(solver, local_targets, seed, on_device=True)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

import torch

__all__ = ["ik_route", "solve_part_ik"]


def ik_route(solver: Any, route_on_host: bool, sim_device: Any) -> tuple[bool, torch.device]:
    """``(on_device, device)``: whether ``solver`` starts on the sim's device (the device
    route and a solver with ``ik_on_device``), and where its targets and seeds go."""
    on_device = not route_on_host and bool(getattr(solver, "ik_on_device", False))
    return on_device, torch.device(sim_device) if on_device else torch.device("cpu")


def solve_part_ik(
    solver: Any, local: torch.Tensor, seed: torch.Tensor, on_device: bool
) -> tuple[torch.Tensor, torch.Tensor]:
    """``(success (n,), qpos (n, k))`` of (n, 4, 4) root-frame targets ``local`` from ``seed``
    (both where :func:`ik_route` put them), on the targets' device."""
    if not on_device:
        success, qpos = solver.get_ik(local, qpos_seed=seed)
        return torch.as_tensor(success, dtype=torch.bool), torch.as_tensor(qpos)
    success, qpos = solver.get_ik_on_device(local, seed)
    todo = torch.nonzero(~success).flatten()  # the one read of the solve
    if len(todo) == 0:
        return success, qpos
    ok_host, q_host = solver.get_ik(local[todo].cpu(), qpos_seed=seed[todo].cpu())
    success, qpos = success.clone(), qpos.clone()
    success[todo] = torch.as_tensor(ok_host, dtype=torch.bool).to(success.device)
    qpos[todo] = torch.as_tensor(q_host).to(qpos.device, qpos.dtype)
    return success, qpos
