"""Simulation helpers: batched per-env model writes and stepping a subset of envs, all
through the core's simulation interface (``env.sim``,
:class:`~embodichain_core.sim.backend.SimBackend`).

The backend defers the recompute of derived constants after writes of a field
that MuJoCo derives them from (masses, positions...): :func:`write_model` writes
every field of one call and the recompute runs once, before the envs are next used.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import numpy as np
import torch

from embodichain_core.sim.backend import field_selector, np_ids
from embodichain_core.utils.math import matrix_to_pose

Write = tuple[str, Any, Any]
"""``(field name, index into the field, values)`` (values broadcast to ``(n,) + field[index]``)."""


def _numpy(values: Any) -> np.ndarray:
    if isinstance(values, np.ndarray):
        return values
    if isinstance(values, torch.Tensor):
        return values.detach().cpu().numpy()
    return np.asarray(values)


def write_model(sim: Any, env_ids: Any, writes: Iterable[Write], set_const: bool = True) -> None:
    """Write per-env model fields of ``env_ids``; one deferred constants update per call.

    Args:
        sim: the env's simulation backend (``env.sim``).
        env_ids: envs to write (long tensor or array).
        writes: ``(name, index, values)`` triples; an ``index`` list selects several
            elements (values then have shape ``(n, k, ...)``).
        set_const: recompute MuJoCo's derived constants when a written field feeds them.
    """
    ids = np_ids(env_ids, sim.num_envs)
    if len(ids) == 0:
        return
    for name, index, values in writes:  # the backend schedules the constants update, run once
        sim.set_model_field(name, ids, index, _numpy(values), set_const=set_const)
    sim.mark_dirty(ids)


def read_model(sim: Any, name: str, env_ids: Any, index: Any) -> np.ndarray:
    """Per-env values ``field[env_ids, index]`` (a copy)."""
    return np.array(sim.model_field(name)[field_selector(np_ids(env_ids, sim.num_envs), index)])


def base_model_value(scene: Any, name: str, index: Any) -> np.ndarray:
    """The compiled model's value (the configured default, before any randomization)."""
    return np.array(getattr(scene.model, name)[index])


def step_envs(env: Any, env_ids: Any, nsteps: int) -> list[int]:
    """Advance only ``env_ids`` by ``nsteps`` physics steps (the others keep their state).

    Returns:
        The envs that diverged. The backend reports them again at the env's next step,
        which truncates and resets them (``info["diverged"]``, a ``RuntimeWarning``).
    """
    if nsteps <= 0:
        return []
    return env.sim.step(int(nsteps), env_ids=np_ids(env_ids, env.sim.num_envs))


def pose7_from_matrix(mat: torch.Tensor) -> torch.Tensor:
    """(..., 4, 4) to (..., 7) float64 xyz + wxyz (:func:`~embodichain_core.utils.math.matrix_to_pose`)."""
    return matrix_to_pose(mat.to(torch.float64))


def uids_matching(names: Sequence[str], prefix: str) -> list[int]:
    """Indices of ``names`` equal to ``prefix`` or starting with ``prefix + '/'``."""
    return [i for i, n in enumerate(names) if n == prefix or n.startswith(prefix + "/")]
