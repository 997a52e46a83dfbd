"""Simulation helpers: batched per-env model writes and stepping a subset of envs.

``BatchSim`` defers ``mj_setConst`` after writes of a field
that MuJoCo derives constants from (masses, positions...). A functor writing
several such fields would pay it several times; :func:`write_model` writes all
fields of one call and runs ``mj_setConst`` once, for the envs written.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.sim.env_rows import batch_ids, field_selector, np_ids
from embodichain_core.utils.math import matrix_to_pose

_SETCONST = frozenset(mujoco.MjModel._setconst_inputs)
_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)

Write = tuple[str, Any, Any]
"""``(field name, index into the field, values)`` (values broadcast to ``(n,) + field[index]``)."""


def _numpy(values: Any) -> np.ndarray:
    if isinstance(values, np.ndarray):
        return values
    if isinstance(values, torch.Tensor):
        return values.detach().cpu().numpy()
    return np.asarray(values)


def write_model(sim: Any, env_ids: Any, writes: Iterable[Write], set_const: bool = True) -> None:
    """Write per-env model fields of ``env_ids``; at most one ``mj_setConst`` per call.

    Args:
        sim: the env's :class:`BatchSim`.
        env_ids: envs to write (long tensor or array).
        writes: ``(name, index, values)`` triples; an ``index`` list selects several
            elements (values then have shape ``(n, k, ...)``).
        set_const: recompute MuJoCo's derived constants when a written field feeds them.
    """
    ids = np_ids(env_ids, sim.num_envs)
    if len(ids) == 0:
        return
    const_fields = []
    for name, index, values in writes:
        sim.set_model_field(name, ids, index, _numpy(values), set_const=False)
        if name in _SETCONST:
            const_fields.append((name, index))
    if const_fields and set_const:
        sim.mark_const_dirty(ids, const_fields)  # one deferred constants update for every write of a reset
    sim.mark_dirty(ids)


def read_model(sim: Any, name: str, env_ids: Any, index: Any) -> np.ndarray:
    """Per-env values ``field[env_ids, index]`` (a copy)."""
    return np.array(sim.model_field(name)[field_selector(np_ids(env_ids, sim.num_envs), index)])


def base_model_value(scene: Any, name: str, index: Any) -> np.ndarray:
    """The compiled model's value (the configured default, before any randomization)."""
    return np.array(getattr(scene.model, name)[index])


def step_envs(env: Any, env_ids: Any, nsteps: int) -> None:
    """Advance only ``env_ids`` by ``nsteps`` physics steps (the others keep their state)."""
    if nsteps <= 0:
        return
    sim = env.sim
    ids = np_ids(env_ids, sim.num_envs)
    sim.forward(ids)  # stepping starts from up-to-date derived fields
    try:
        sim.batch.step(batch_ids(ids, sim.num_envs), nstep=int(nsteps) * sim.substeps, stage=_VEL)
    except Exception:  # a diverging env surfaces as non-finite state on the env's next step
        pass


def pose7_from_matrix(mat: torch.Tensor) -> torch.Tensor:
    """(..., 4, 4) to (..., 7) float64 xyz + wxyz (:func:`~embodichain_core.utils.math.matrix_to_pose`)."""
    return matrix_to_pose(mat.to(torch.float64))


def uids_matching(names: Sequence[str], prefix: str) -> list[int]:
    """Indices of ``names`` equal to ``prefix`` or starting with ``prefix + '/'``."""
    return [i for i, n in enumerate(names) if n == prefix or n.startswith(prefix + "/")]
