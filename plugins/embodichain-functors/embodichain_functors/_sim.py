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


def rows_of(env_ids: Any) -> np.ndarray:
    """``env_ids`` as a 1-D int64 numpy array (no copy for a CPU long tensor)."""
    if isinstance(env_ids, torch.Tensor) and env_ids.dtype == torch.long and env_ids.dim() == 1 \
            and env_ids.device.type == "cpu":
        return env_ids.numpy()
    return _numpy(env_ids).astype(np.int64).reshape(-1)


def _is_list(index: Any) -> bool:
    return isinstance(index, (list, np.ndarray, torch.Tensor))


def _selector(ids: np.ndarray, index: Any) -> tuple:
    """``field[selector]`` of ``index`` for ``ids``; a list (first) index selects several elements."""
    if isinstance(index, int):
        return ids, index
    if _is_list(index):
        return ids[:, None], _numpy(index).astype(np.int64)[None, :]
    if isinstance(index, tuple) and index and _is_list(index[0]):
        return (ids[:, None], _numpy(index[0]).astype(np.int64)[None, :]) + index[1:]
    if isinstance(index, tuple):
        return (ids,) + index
    return ids, index


def batch_ids(ids: np.ndarray, num_envs: int) -> Any:
    """``ids`` as the batch expects them (``None`` for every env)."""
    unique = np.unique(ids).astype(np.int32)
    return None if len(unique) == num_envs else unique


def write_model(sim: Any, env_ids: Any, writes: Iterable[Write], set_const: bool = True) -> None:
    """Write per-env model fields of ``env_ids``; at most one ``mj_setConst`` per call.

    Args:
        sim: the env's :class:`BatchSim`.
        env_ids: envs to write (long tensor or array).
        writes: ``(name, index, values)`` triples; an ``index`` list selects several
            elements (values then have shape ``(n, k, ...)``).
        set_const: recompute MuJoCo's derived constants when a written field feeds them.
    """
    ids = rows_of(env_ids)
    if len(ids) == 0:
        return
    if sim.env_models is not None:  # per-env models: the core writes each model
        for name, index, values in writes:
            sim.set_model_field(name, ids, index, _numpy(values))
        return
    const_fields = []
    for name, index, values in writes:
        sim.batch.expand(name)[_selector(ids, index)] = _numpy(values)
        if name in _SETCONST:
            const_fields.append((name, index))
    if const_fields and set_const:
        sim.mark_const_dirty(ids, const_fields)  # one deferred mj_setConst for every write of a reset
    sim.mark_dirty(ids)


def read_model(sim: Any, name: str, env_ids: Any, index: Any) -> np.ndarray:
    """Per-env values ``field[env_ids, index]`` (a copy)."""
    return np.array(sim.model_field(name)[_selector(rows_of(env_ids), index)])


def base_model_value(scene: Any, name: str, index: Any) -> np.ndarray:
    """The compiled model's value (the configured default, before any randomization)."""
    return np.array(getattr(scene.model, name)[index])


def step_envs(env: Any, env_ids: Any, nsteps: int) -> None:
    """Advance only ``env_ids`` by ``nsteps`` physics steps (the others keep their state)."""
    if nsteps <= 0:
        return
    sim = env.sim
    ids = rows_of(env_ids)
    sim.forward(ids)  # stepping starts from up-to-date derived fields
    try:
        sim.batch.step(batch_ids(ids, sim.num_envs), nstep=int(nsteps) * sim.substeps, stage=_VEL)
    except Exception:  # a diverging env surfaces as non-finite state on the env's next step
        pass


def quat_from_matrix(mat: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) rotation matrices to (..., 4) wxyz quaternions, vectorized (w >= 0)."""
    m = mat.to(torch.float64)
    trace = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    cands = torch.stack((
        torch.stack((1 + trace, m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0],
                     m[..., 1, 0] - m[..., 0, 1]), -1),
        torch.stack((m[..., 2, 1] - m[..., 1, 2], 1 + m[..., 0, 0] - m[..., 1, 1] - m[..., 2, 2],
                     m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0]), -1),
        torch.stack((m[..., 0, 2] - m[..., 2, 0], m[..., 0, 1] + m[..., 1, 0],
                     1 - m[..., 0, 0] + m[..., 1, 1] - m[..., 2, 2], m[..., 1, 2] + m[..., 2, 1]), -1),
        torch.stack((m[..., 1, 0] - m[..., 0, 1], m[..., 0, 2] + m[..., 2, 0], m[..., 1, 2] + m[..., 2, 1],
                     1 - m[..., 0, 0] - m[..., 1, 1] + m[..., 2, 2]), -1),
    ), -2)
    diag = torch.stack((trace, m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]), -1)
    best = diag.argmax(-1, keepdim=True)
    q = torch.gather(cands, -2, best[..., None].expand(best.shape + (4,))).squeeze(-2)
    q = q / q.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    return torch.where(q[..., :1] < 0, -q, q)


def pose7_from_matrix(mat: torch.Tensor) -> torch.Tensor:
    """(..., 4, 4) to (..., 7) xyz + wxyz."""
    return torch.cat((mat[..., :3, 3].to(torch.float64), quat_from_matrix(mat[..., :3, :3])), -1)


def uids_matching(names: Sequence[str], prefix: str) -> list[int]:
    """Indices of ``names`` equal to ``prefix`` or starting with ``prefix + '/'``."""
    return [i for i, n in enumerate(names) if n == prefix or n.startswith(prefix + "/")]
