"""Deferred derived-constant updates of a :class:`~embodichain_core.sim.backend.batch_sim.BatchSim`.

Writing a model field MuJoCo derives constants from (``mujoco.MjModel._setconst_inputs``:
masses, inertial frames, light positions...) schedules a recompute for the envs
written; :meth:`BatchConstants.flush_const` runs it once before the next step, forward
or host copy. Envs where only free bodies' inertial properties (or collision filters)
changed take the closed form of :mod:`embodichain_core.sim.backend.free_body_const`;
the others run ``mj_setConst`` on the whole model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Iterable, Optional

import mujoco
import numpy as np

from embodichain_core.sim.backend.env_rows import batch_ids as _batch_ids
from embodichain_core.sim.backend.env_rows import index_bodies as _index_bodies
from embodichain_core.sim.backend.env_rows import np_ids as _np_ids
from embodichain_core.sim.backend.free_body_const import (
    FILTER_FIELDS,
    INERTIAL_FIELDS,
    FreeBodyConstants,
    eligible_bodies,
)


class BatchConstants:
    """Mixin of :class:`BatchSim` (which provides ``model``, ``batch``, ``num_envs``,
    ``env_models``, ``_set_const_models`` and the ``_const_*``/``_closed_form_*`` flags)."""

    model: mujoco.MjModel
    batch: Any
    num_envs: int
    env_models: Optional[list[mujoco.MjModel]]
    _const_dirty: np.ndarray  # (num_envs,) bool: a full mj_setConst is due
    _closed_form_dirty: np.ndarray  # (num_envs,) bool: a closed-form update is due
    _closed_form_fields: set[str]  # the fields written since the last flush
    _const_pending: bool
    _fast_constants: bool
    _free_bodies: Optional[np.ndarray]
    _free_const: Optional[FreeBodyConstants]

    if TYPE_CHECKING:  # defined by PerEnvModels

        def _set_const_models(self, ids: Iterable[int]) -> None: ...

    def mark_const_dirty(self, env_ids: Any = None, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Note that constant inputs of ``env_ids`` changed (written directly into
        expanded fields); ``mj_setConst`` runs once before they are next used.

        ``fields`` (``(name, index)`` pairs of what was written) lets a write of only
        free bodies' masses and inertial frames, or of geoms' collision filters, take
        the closed form (:mod:`embodichain_core.sim.backend.free_body_const`); without it the
        full one runs.
        """
        ids = _np_ids(env_ids, self.num_envs)
        fields = None if fields is None else list(fields)
        if fields is not None and self._all_closed_form_fields(fields):
            self._closed_form_dirty[ids] = True
            self._closed_form_fields.update(name for name, _ in fields)
        else:
            self._const_dirty[ids] = True
        self._const_pending = True

    def _all_closed_form_fields(self, fields: Iterable[tuple[str, Any]]) -> bool:
        for name, index in fields:
            if not self._closed_form_field(name, index):
                return False
        return True

    def _closed_form_field(self, name: str, index: Any) -> bool:
        """Whether a write of ``name[index]`` is one the closed form absorbs."""
        if not self._fast_constants or self.env_models is not None:
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
        bodies = _index_bodies(index)
        return bodies is not None and bool(eligible[bodies].all())

    def _eligible_bodies(self) -> np.ndarray:
        """``(nbody,)`` mask of the free bodies whose constants have a closed form."""
        if self._free_bodies is None:
            self._free_bodies = np.zeros(self.model.nbody, dtype=bool)
            self._free_bodies[eligible_bodies(self.model)] = True
        return self._free_bodies

    def flush_const(self) -> None:
        """Recompute MuJoCo's derived constants once for every env whose inputs changed.

        Deferred from :meth:`set_model_field` so that a reset writing several fields
        (mass, centre of mass, light position) pays for one call; run automatically
        before stepping, forward and ``get_model``/``get_data``. Envs where only free
        bodies' inertial properties changed get them in closed form
        (:mod:`embodichain_core.sim.backend.free_body_const`); the others run
        ``mj_setConst`` on the whole model.
        """
        if not self._const_pending:
            return
        self._const_pending = False
        full = np.flatnonzero(self._const_dirty)
        fast = np.flatnonzero(self._closed_form_dirty & ~self._const_dirty)
        self._const_dirty[:] = False
        self._closed_form_dirty[:] = False
        written, self._closed_form_fields = self._closed_form_fields, set()
        if len(fast) and not self._free_body_constants().update(fast, written):
            full = np.union1d(full, fast).astype(np.int64)  # a case the closed form does not cover
        if not len(full):
            return
        if self.env_models is not None:
            self._set_const_models(full)
            self.batch.set_models(self.env_models)
        else:
            self.batch.set_const(_batch_ids(full, self.num_envs))

    def _free_body_constants(self) -> FreeBodyConstants:
        """The closed-form constants of the eligible free bodies (built on first use)."""
        if self._free_const is None:
            bodies = np.flatnonzero(self._eligible_bodies()).tolist()
            self._free_const = FreeBodyConstants(self.model, self.batch, bodies)
        return self._free_const
