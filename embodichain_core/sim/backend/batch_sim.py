"""The CPU backend: ``num_envs`` simulations on ``mujoco.batch.Batch`` (MuJoCo >= 4.0).

One state row per env, stepped on a thread pool with the GIL released and
bit-identical to a loop. It implements :class:`~embodichain_core.sim.backend.interface.SimBackend`:
state and derived fields are zero-copy float64 torch views of the one batch, created
once (and numpy views, ``arrays``), forward is lazy (:meth:`BatchSim.mark_dirty`), any
subset of envs steps natively. Per-env model fields are expanded fields
(``Batch.expand``) of the one model structure every env shares.

Derived constants after model writes: :mod:`.batch_constants` (a
:class:`~embodichain_core.sim.backend.batch_constants.DeferredConstants` the backend
owns). ``BatchSim.batch`` (the ``mujoco.batch.Batch``) is this backend's own business:
code outside ``sim/backend/`` goes through the interface.
"""

from __future__ import annotations

import math
import os
import warnings
from typing import Any, Iterable, Optional

import mujoco
import mujoco.batch as mjbatch
import numpy as np
import torch

from embodichain_core.sim.backend.batch_constants import DeferredConstants
from embodichain_core.sim.backend.env_rows import batch_ids as _batch_ids
from embodichain_core.sim.backend.env_rows import field_selector as _field_selector
from embodichain_core.sim.backend.env_rows import np_ids as _np_ids
from embodichain_core.sim.backend.field_views import FieldViews
from embodichain_core.sim.backend.interface import DERIVED_FIELDS, STATE_FIELDS, SimCapabilities

_VEL = int(mujoco.mjtStage.mjSTAGE_VEL)
_NONE = int(mujoco.mjtStage.mjSTAGE_NONE)
_SETCONST_INPUTS = frozenset(mujoco.MjModel._setconst_inputs)
CAPABILITIES = SimCapabilities(subset_step=True, host_arrays=True, float64=True, deterministic=True)


class BatchSim(FieldViews):
    """``num_envs`` MuJoCo simulations of one compiled model.

    Args:
        model: the compiled scene.
        num_envs: simulations (one state row each).
        substeps: MuJoCo steps per :meth:`step`.
        nthread: batch threads (0: one per core, at most ``num_envs``).
        persistent: keep the thread pool between calls.
    """

    restores_state_rows = True
    """:meth:`reset` takes a saved state row (``state=``)."""

    def __init__(
        self,
        model: mujoco.MjModel,
        num_envs: int,
        substeps: int = 1,
        nthread: int = 0,
        persistent: bool = True,
    ):
        self.model = model
        self.num_envs = int(num_envs)
        self.substeps = int(substeps)
        self.nthread = int(nthread) or min(os.cpu_count() or 1, self.num_envs)
        self.persistent = persistent
        self.device = torch.device("cpu")
        self.dtype = torch.float64
        self.capabilities = CAPABILITIES
        self._dirty = np.zeros(self.num_envs, dtype=bool)
        self._maybe_dirty = False  # False: no env is dirty (skips the scan on every read)
        self._pending_failed: list[int] = []  # failures of forwards and subset steps, for the next full step
        self.batch = mjbatch.Batch(model, self.num_envs, nthread=self.nthread, persistent=persistent)
        self.constants = DeferredConstants(model, self.batch)
        """The derived constants due after model-field writes (:mod:`.batch_constants`)."""
        self._views: dict[str, torch.Tensor] = {}
        self.arrays: dict[str, np.ndarray] = {}
        """Numpy views of the state fields (same memory as the torch views): the cheap
        way to write a few values of a few envs (then call :meth:`mark_dirty`)."""
        self._bind_views()
        self.batch.reset(None)

    def _bind_views(self) -> None:
        """The persistent views: the batch is made once, so they hold for the backend's lifetime."""
        for name in STATE_FIELDS:
            self.arrays[name] = self.batch.bind(name)
            self._views[name] = torch.from_numpy(self.arrays[name])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # outputs are read-only numpy arrays
            for name in DERIVED_FIELDS:
                try:
                    self._views[name] = torch.from_numpy(self.batch.bind(name))
                except (ValueError, AttributeError):
                    continue

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
    def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
        """Advance ``env_ids`` (``None``: every env) by ``nstep`` physics steps; return the
        envs that diverged (MuJoCo raised, or the state went non-finite).

        A subset step forwards its envs first (it usually follows direct state writes)
        and leaves the other envs untouched. Failures of a subset step, or of a
        forward (lazy or explicit), are reported again by the next step of every env,
        which the env loop truncates and resets.
        """
        if self.constants.pending:
            self.flush_const()
        if env_ids is None:
            if self._maybe_dirty:
                self._forward_dirty()
            failed = self._step_rows(None, nstep)
            if self._pending_failed:
                failed, self._pending_failed = sorted(set(failed) | set(self._pending_failed)), []
            return failed
        rows = np.unique(_np_ids(env_ids, self.num_envs))
        if not len(rows):
            return []
        before = set(self._pending_failed)
        self.forward(rows)
        failed = sorted(set(self._step_rows(rows, nstep)) | (set(self._pending_failed) - before))
        self._pending_failed = sorted(before | set(failed))
        return failed

    def _step_rows(self, rows: Optional[np.ndarray], nstep: int) -> list[int]:
        """``Batch.step`` of ``rows`` (None: all) at ``stage=VEL``; the failed and non-finite rows."""
        failed: list[int] = []
        ids = _batch_ids(rows, self.num_envs)
        try:
            self.batch.step(ids, nstep * self.substeps, _VEL)
        except mjbatch.SimulationError as err:
            failed = [int(i) for i in err.ids]
        state = self.batch.state if rows is None else self.batch.state[rows]
        if math.isfinite(state.sum()):  # a sum is finite only if every value is (cheap prefilter)
            return failed
        bad = ~np.isfinite(state).all(axis=1)
        if bad.any():
            bad_ids = np.flatnonzero(bad) if rows is None else rows[bad]
            failed = sorted(set(failed) | set(bad_ids.tolist()))
        return failed

    def forward(self, env_ids: Any = None) -> None:
        """Recompute derived fields (kinematics, sensors) of ``env_ids``."""
        self.flush_const()
        ids = _batch_ids(env_ids, self.num_envs)
        try:
            self.batch.forward(ids, stage=_VEL)
        except mjbatch.SimulationError as err:  # reported by the next step of every env
            self._pending_failed = sorted(set(self._pending_failed) | {int(i) for i in err.ids})
        self._dirty[_np_ids(env_ids, self.num_envs)] = False

    def reset(self, env_ids: Any = None, state: Optional[np.ndarray] = None) -> None:
        """Reset ``env_ids`` to the model defaults (qpos0, zero velocities, zero controls),
        then with ``state`` write that saved ``(nstate,)`` row into them (one write, see
        :mod:`embodichain_core.sim.scene_defaults`); failures of theirs not reported yet
        are dropped."""
        # no forward here: resets are followed by state writes; derived fields are
        # recomputed lazily when next read (or before the next step). The MuJoCo reset
        # runs in any case: it also clears the derived fields a forward does not
        # recompute (qfrc_actuator, ...) and whatever a diverged simulation left there.
        rows = _np_ids(env_ids, self.num_envs)  # converted once (a reset runs rarely, with cold caches)
        ids = _batch_ids(rows, self.num_envs)
        self.batch.reset(ids, stage=_NONE)
        if state is not None:
            self.batch.state[rows if ids is not None else slice(None)] = state
        self.mark_dirty(rows)
        if self._pending_failed:  # a reset state has nothing left to report
            reset = set(rows.tolist())
            self._pending_failed = [i for i in self._pending_failed if i not in reset]

    def error(self, env_id: int) -> str:
        return self.batch.error(int(env_id))

    # -- per-env model fields -----------------------------------------------------------------
    def model_field(self, name: str) -> np.ndarray:
        """Read-only (num_envs, ...) values of a model field (shared fields broadcast)."""
        values = self.batch.expanded(name)
        if values is None:
            base = getattr(self.model, name)
            values = np.broadcast_to(base, (self.num_envs,) + base.shape)
        return values

    def model_tensor(self, name: str) -> torch.Tensor:
        """:meth:`model_field` as a CPU tensor (a view of per-env values, else the shared
        values expanded)."""
        values = self.batch.expanded(name)
        if values is not None:
            return torch.from_numpy(values)
        base = torch.from_numpy(np.array(getattr(self.model, name)))
        return base.expand((self.num_envs,) + tuple(base.shape))

    def declare_per_env(self, names: Iterable[str]) -> None:
        """Give model fields per-env values now (``Batch.expand``)."""
        for name in names:
            self.batch.expand(name)

    def is_per_env(self, name: str) -> bool:
        """Whether model field ``name`` holds per-env values (is expanded)."""
        return self.batch.expanded(name) is not None

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
        self.batch.expand("body_inertia")[sel] *= ratio
        self.batch.expand("body_mass")[sel] = mass
        self.mark_const_dirty(rows, (("body_mass", bodies), ("body_inertia", bodies)))

    def get_model(self, env_id: int, model: Optional[mujoco.MjModel] = None) -> mujoco.MjModel:
        """The model env ``env_id`` runs on (for rendering or any mj_ function).

        Pass ``model`` (a copy of ``self.model`` kept by the caller) to have it
        filled in place instead of allocating a copy per call.
        """
        self.flush_const()
        return self.batch.get_model(int(env_id), model)

    def get_data(self, env_id: int, data: Optional[mujoco.MjData] = None) -> mujoco.MjData:
        """Env ``env_id``'s MjData (whole in a persistent batch)."""
        self.flush_const()
        if self._dirty[int(env_id)]:
            self.forward([int(env_id)])
        return self.batch.get_data(int(env_id), data)

    # -- derived constants ----------------------------------------------------------------------
    def mark_const_dirty(self, env_ids: Any = None, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Note that constant inputs of ``env_ids`` changed (written directly into
        expanded fields); they are recomputed once before they are next used.

        ``fields`` (``(name, index)`` pairs of what was written) lets a write of only
        free bodies' masses and inertial frames, or of geoms' collision filters, take
        the closed form (:mod:`embodichain_core.sim.backend.free_body_const`); without it the
        full ``mj_setConst`` runs.
        """
        self.constants.mark(_np_ids(env_ids, self.num_envs), fields)

    def flush_const(self) -> None:
        """Recompute MuJoCo's derived constants once for every env whose inputs changed.

        Deferred from :meth:`set_model_field` so that a reset writing several fields
        (mass, centre of mass, light position) pays for one call; run automatically
        before stepping, forward and ``get_model``/``get_data``.
        """
        if self.constants.pending:
            full = self.constants.flush()
            if len(full):
                self.batch.set_const(_batch_ids(full, self.num_envs))
