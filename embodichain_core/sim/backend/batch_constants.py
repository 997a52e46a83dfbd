"""Deferred derived-constant updates of a :class:`~embodichain_core.sim.backend.batch_sim.BatchSim`.

Writing a model field MuJoCo derives constants from (``mujoco.MjModel._setconst_inputs``:
masses, inertial frames, light positions...) schedules a recompute for the envs
written (:meth:`DeferredConstants.mark`); the backend's ``flush_const`` runs it once
before the next step, forward or host copy. Envs where only free bodies' inertial
properties (or collision filters) changed take the closed form of
:mod:`embodichain_core.sim.backend.free_body_const`; the others need ``mj_setConst`` on
the whole model, which the backend runs on the rows :meth:`DeferredConstants.flush`
returns.
"""

from __future__ import annotations

from typing import Any, Iterable, Optional

import mujoco
import numpy as np

from embodichain_core.sim.backend.env_rows import index_bodies
from embodichain_core.sim.backend.free_body_const import (
    FILTER_FIELDS,
    INERTIAL_FIELDS,
    FreeBodyConstants,
    eligible_bodies,
)


class DeferredConstants:
    """Which envs' derived constants are due, and the closed form for those it covers.

    Args:
        model: the compiled model (the structure every env shares).
        batch: the ``mujoco.batch.Batch`` whose expanded fields the closed form writes.
    """

    def __init__(self, model: mujoco.MjModel, batch: Any):
        self.model = model
        self.batch = batch
        self.fast = True
        """Take the closed form where it applies (False: always the whole model's
        ``mj_setConst``, the reference the closed form is tested against)."""
        self.pending = False
        """Whether any env's constants are due (checked before every step: one attribute read)."""
        self.free_const: Optional[FreeBodyConstants] = None
        """The closed form of the eligible free bodies (built on first use)."""
        self._full = np.zeros(batch.nsim, dtype=bool)  # a full mj_setConst is due
        self._closed = np.zeros(batch.nsim, dtype=bool)  # a closed-form update is due
        self._fields: set[str] = set()  # the fields written since the last flush
        self._eligible: Optional[np.ndarray] = None

    def mark(self, rows: np.ndarray, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Note that constant inputs of env ``rows`` changed; ``fields`` (``(name, index)``
        pairs of what was written) lets writes the closed form covers take it."""
        fields = None if fields is None else list(fields)
        if fields is not None and all(self.closed_form_field(name, index) for name, index in fields):
            self._closed[rows] = True
            self._fields.update(name for name, _ in fields)
        else:
            self._full[rows] = True
        self.pending = True

    def closed_form_field(self, name: str, index: Any) -> bool:
        """Whether a write of ``name[index]`` is one the closed form absorbs."""
        if not self.fast:
            return False
        if name in FILTER_FIELDS:  # any geom's: only the bodies' aggregate filters follow
            return True
        if name not in INERTIAL_FIELDS:
            return False
        eligible = self._eligible_bodies()
        if isinstance(index, (int, np.integer)):
            return bool(eligible[index])
        if isinstance(index, np.ndarray) and index.dtype.kind in "iu":
            return bool(eligible[index].all())
        bodies = index_bodies(index)
        return bodies is not None and bool(eligible[bodies].all())

    def flush(self) -> np.ndarray:
        """Run the closed form where it is due and covers the values; return the sorted
        env rows that still need ``mj_setConst`` on the whole model (and clear them)."""
        self.pending = False
        full = np.flatnonzero(self._full)
        fast = np.flatnonzero(self._closed & ~self._full)
        self._full[:] = False
        self._closed[:] = False
        written, self._fields = self._fields, set()
        if len(fast) and not self._free_body_constants().update(fast, written):
            full = np.union1d(full, fast).astype(np.int64)  # a case the closed form does not cover
        return full

    def _eligible_bodies(self) -> np.ndarray:
        """``(nbody,)`` mask of the free bodies whose constants have a closed form."""
        if self._eligible is None:
            self._eligible = np.zeros(self.model.nbody, dtype=bool)
            self._eligible[eligible_bodies(self.model)] = True
        return self._eligible

    def _free_body_constants(self) -> FreeBodyConstants:
        if self.free_const is None:
            bodies = np.flatnonzero(self._eligible_bodies()).tolist()
            self.free_const = FreeBodyConstants(self.model, self.batch, bodies)
        return self.free_const
