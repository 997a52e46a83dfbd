"""Batched simulation backend: ``num_envs`` simulations on ``mujoco.batch.Batch``.

One state row per env, stepped on a thread pool with the GIL released and
bit-identical to a loop. State fields are exposed as zero-copy torch views
(float64) created once. Per-env model fields come in two ways:

* expanded fields (``Batch.expand``): cheap, while envs share one structure;
* per-env models (``Batch.set_models``), once envs differ in structure (a
  different mesh per env). Switching rebuilds the batch and copies the state.

This class is the only stepping path; a GPU backend would implement the same
small interface (``step``, ``reset``, ``forward``, state views, model fields).
"""

from __future__ import annotations

import os
import warnings
from typing import Any, Iterable, Optional

import mujoco
import mujoco.batch as mjbatch
import numpy as np
import torch

from embodichain_core.sim.batch_env_models import PerEnvModels
from embodichain_core.sim.env_rows import batch_ids as _batch_ids
from embodichain_core.sim.env_rows import field_selector as _field_selector
from embodichain_core.sim.env_rows import index_bodies as _index_bodies
from embodichain_core.sim.env_rows import np_ids as _np_ids
from embodichain_core.sim.free_body_const import FILTER_FIELDS, INERTIAL_FIELDS, FreeBodyConstants, eligible_bodies

STATE_FIELDS = ("qpos", "qvel", "act", "ctrl", "qfrc_applied", "xfrc_applied", "mocap_pos", "mocap_quat", "eq_active")
OUTPUT_FIELDS = ("xpos", "xquat", "xmat", "cvel", "site_xpos", "site_xmat", "qfrc_actuator", "actuator_force",
                 "cfrc_ext", "qacc", "sensordata", "light_xpos", "light_xdir", "cam_xpos", "cam_xmat", "geom_xpos",
                 "geom_xmat", "ncon")
_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)
_SETCONST_INPUTS = frozenset(mujoco.MjModel._setconst_inputs)


class SimulationDiverged(RuntimeError):
    """Some envs' simulations failed; ``env_ids`` lists them."""

    def __init__(self, env_ids: list[int], messages: list[str]):
        self.env_ids, self.messages = env_ids, messages
        super().__init__(f"simulation diverged in envs {env_ids}: {messages[:1]}")


class BatchSim(PerEnvModels):
    """``num_envs`` MuJoCo simulations of one compiled model.

    Args:
        model: the compiled scene.
        num_envs: simulations (one state row each).
        substeps: MuJoCo steps per :meth:`step`.
        nthread: batch threads (0: one per core, at most ``num_envs``).
        persistent: keep the thread pool between calls.
        fast_constants: derive what the closed form covers without ``mj_setConst``
            (False: always the whole model's, e.g. as a reference in tests).
    """

    def __init__(self, model: mujoco.MjModel, num_envs: int, substeps: int = 1, nthread: int = 0,
                 persistent: bool = True, fast_constants: bool = True):
        self.model = model
        self.num_envs = int(num_envs)
        self.substeps = int(substeps)
        self.nthread = int(nthread) or min(os.cpu_count() or 1, self.num_envs)
        self.persistent = persistent
        self.env_models: Optional[list[mujoco.MjModel]] = None
        self._dirty = np.zeros(self.num_envs, dtype=bool)
        self._maybe_dirty = False  # False: no env is dirty (skips the scan on every read)
        self._const_dirty = np.zeros(self.num_envs, dtype=bool)  # full mj_setConst due
        self._closed_form_dirty = np.zeros(self.num_envs, dtype=bool)  # closed-form update due
        self._closed_form_fields: set[str] = set()  # the fields written since then
        self._const_pending = False
        self._fast_constants = fast_constants  # closed form where it applies (else always mj_setConst)
        self._free_bodies: Optional[np.ndarray] = None  # see _eligible_bodies
        self._free_const: Optional[FreeBodyConstants] = None
        self._make_batch()
        self.batch.reset(None)

    # -- construction and views --------------------------------------------------------------
    def _make_batch(self) -> None:
        self.batch = mjbatch.Batch(self.model, self.num_envs, nthread=self.nthread, persistent=self.persistent)
        self._free_const = None
        self._views: dict[str, torch.Tensor] = {}
        self.arrays: dict[str, np.ndarray] = {}
        """Numpy views of the state fields (same memory as the torch views): the cheap
        way to write a few values of a few envs (then call :meth:`mark_dirty`)."""
        for name in STATE_FIELDS:
            self.arrays[name] = self.batch.bind(name)
            self._views[name] = torch.from_numpy(self.arrays[name])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # outputs are read-only numpy arrays
            for name in OUTPUT_FIELDS:
                try:
                    self._views[name] = torch.from_numpy(self.batch.bind(name))
                except (ValueError, AttributeError):
                    continue

    def __getattr__(self, name: str) -> torch.Tensor:
        views = self.__dict__.get("_views")
        if views is not None and name in views:
            if self._maybe_dirty and name not in STATE_FIELDS:
                self._forward_dirty()
            return views[name]
        raise AttributeError(f"BatchSim has no field {name!r}")

    @property
    def state(self) -> np.ndarray:
        """The raw (num_envs, nstate) integration state rows."""
        return self.batch.state

    def mark_dirty(self, env_ids: Any = None) -> None:
        """Note that state was written directly; derived fields get recomputed lazily."""
        if env_ids is None:
            self._dirty[:] = True
        else:
            self._dirty[_np_ids(env_ids, self.num_envs)] = True
        self._maybe_dirty = True

    def _forward_dirty(self) -> None:
        """Forward the envs marked dirty (if any)."""
        if self._dirty.any():
            self.forward(np.flatnonzero(self._dirty))
        self._maybe_dirty = False

    # -- stepping ------------------------------------------------------------------------------
    def step(self, nstep: int = 1) -> list[int]:
        """Advance every env by ``nstep`` physics steps; return envs that diverged."""
        self.flush_const()
        self._forward_dirty()
        failed: list[int] = []
        try:
            self.batch.step(nstep=nstep * self.substeps, stage=_VEL)
        except mjbatch.SimulationError as err:
            failed = [int(i) for i in err.ids]
        bad = ~np.isfinite(self.batch.state).all(axis=1)
        if bad.any():
            failed = sorted(set(failed) | set(np.flatnonzero(bad).tolist()))
        return failed

    def forward(self, env_ids: Any = None) -> None:
        """Recompute derived fields (kinematics, sensors) of ``env_ids``."""
        self.flush_const()
        ids = _batch_ids(env_ids, self.num_envs)
        try:
            self.batch.forward(ids, stage=_VEL)
        except mjbatch.SimulationError:
            pass
        self._dirty[_np_ids(env_ids, self.num_envs)] = False

    def reset(self, env_ids: Any = None) -> None:
        """Reset ``env_ids`` to the model defaults (qpos0, zero velocities, zero controls)."""
        ids = _batch_ids(env_ids, self.num_envs)
        # no forward here: resets are followed by state writes; derived fields are
        # recomputed lazily when next read (or before the next step)
        self.batch.reset(ids, stage=int(mujoco.mjtStage.mjSTAGE_NONE))
        self.mark_dirty(env_ids)

    def error(self, env_id: int) -> str:
        return self.batch.error(int(env_id))

    # -- per-env model fields -----------------------------------------------------------------
    def model_field(self, name: str) -> np.ndarray:
        """Read-only (num_envs, ...) values of a model field (shared fields broadcast)."""
        if self.env_models is not None:
            return np.stack([getattr(m, name) for m in self.env_models])
        values = self.batch.expanded(name)
        if values is None:
            base = getattr(self.model, name)
            values = np.broadcast_to(base, (self.num_envs,) + base.shape)
        return values

    def set_model_field(self, name: str, env_ids: Any, index: Any, values: Any, set_const: bool = True) -> None:
        """Write ``values`` into model field ``name[index]`` of each env in ``env_ids``.

        ``values`` broadcasts to ``(len(env_ids),) + field[index].shape`` (a list ``index``,
        or a tuple starting with one, selects several elements: values ``(n, k, ...)``). A field that
        MuJoCo derives constants from schedules one ``mj_setConst`` for these envs
        (before their next forward or step) unless ``set_const=False`` (the caller
        writes the derived values itself).
        """
        ids = _np_ids(env_ids, self.num_envs)
        values = np.asarray(values.detach().cpu().numpy() if isinstance(values, torch.Tensor) else values)
        if self.env_models is not None:
            vals = np.broadcast_to(values, (len(ids),) + np.shape(getattr(self.model, name)[index]))
            for k, env in enumerate(ids):
                getattr(self.env_models[env], name)[index] = vals[k]
            self.batch.set_models(self.env_models)
        else:
            self.batch.expand(name)[_field_selector(ids, index)] = values
        if set_const and name in _SETCONST_INPUTS:
            self.mark_const_dirty(ids, [(name, index)])

    def set_body_masses(self, env_ids: Any, bodies: Any, mass: Any) -> None:
        """Set masses ``(n, k)`` of MuJoCo ``bodies`` in ``env_ids``; their inertias scale
        along (the density distribution is kept). One deferred constants update."""
        rows = _np_ids(env_ids, self.num_envs)
        bodies = np.asarray(bodies, dtype=np.int64).reshape(-1)
        mass = np.broadcast_to(np.asarray(mass, dtype=np.float64), (len(rows), len(bodies)))
        sel = (rows[:, None], bodies[None, :])
        ratio = (mass / np.maximum(self.model_field("body_mass")[sel], 1e-12))[..., None]
        if self.env_models is not None:
            self.set_model_field("body_inertia", rows, bodies, self.model_field("body_inertia")[sel] * ratio)
            self.set_model_field("body_mass", rows, bodies, mass)
            return
        self.batch.expand("body_inertia")[sel] *= ratio
        self.batch.expand("body_mass")[sel] = mass
        self.mark_const_dirty(rows, (("body_mass", bodies), ("body_inertia", bodies)))

    def mark_const_dirty(self, env_ids: Any = None, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Note that constant inputs of ``env_ids`` changed (written directly into
        expanded fields); ``mj_setConst`` runs once before they are next used.

        ``fields`` (``(name, index)`` pairs of what was written) lets a write of only
        free bodies' masses and inertial frames, or of geoms' collision filters, take
        the closed form (:mod:`embodichain_core.sim.free_body_const`); without it the
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
        (:mod:`embodichain_core.sim.free_body_const`); the others run
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

    def get_model(self, env_id: int, model: Optional[mujoco.MjModel] = None) -> mujoco.MjModel:
        """The model env ``env_id`` runs on (for rendering or any mj_ function).

        Pass ``model`` (a copy of ``self.model`` kept by the caller) to have it
        filled in place instead of allocating a copy per call.
        """
        self.flush_const()
        if self.env_models is not None:
            return self.env_models[int(env_id)]
        return self.batch.get_model(int(env_id), model)

    def get_data(self, env_id: int, data: Optional[mujoco.MjData] = None) -> mujoco.MjData:
        """Env ``env_id``'s MjData (whole in a persistent batch)."""
        self.flush_const()
        if self._dirty[int(env_id)]:
            self.forward([int(env_id)])
        return self.batch.get_data(int(env_id), data)

