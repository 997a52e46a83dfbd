"""The ``warp`` backend: ``num_envs`` worlds of one model on MuJoCo Warp (GPU, or Warp's CPU device).

:class:`WarpSim` implements :class:`~embodichain_core.sim.backend.interface.SimBackend`,
so entities, managers, functors and tasks run on it unchanged. What differs from
:class:`~embodichain_core.sim.backend.batch_sim.BatchSim` (see docs/backends.md):

* **float32** state and views (``wp.to_torch`` of MuJoCo Warp's arrays, zero-copy, on the
  sim device; ``sim.tensors`` maps the state fields to them); on Warp's CPU device
  ``sim.arrays`` are numpy views of the same memory (``capabilities.host_arrays``), on a
  GPU there are none (:func:`~embodichain_core.sim.backend.warp_device.host_arrays_for`).
* **No subset stepping** (``capabilities.subset_step`` is False): a subset step steps every
  world, then puts the other envs' state back (a copy: slow, exact for those envs).
* **Forward and constants cover every world** (MuJoCo Warp has no world subset); a step
  ends with a position-velocity refresh (``mujoco_warp.step1``'s stages), so derived
  views are current as after ``mujoco.batch``'s ``stage=VEL`` step, but acceleration
  sensors read zero.
* **Resets** through ``reset_data`` with a per-world mask; **per-env model fields** only
  those MuJoCo Warp batches (:mod:`.warp_fields`), held by the
  :class:`~embodichain_core.sim.backend.warp_model.WarpModelFields` the backend owns
  (``sim.fields``).
* **Graphs**: the step, the refresh and the reset are captured once and replayed
  (:mod:`.warp_device`): CUDA graphs on a GPU (untested: no GPU was lent to this work),
  Warp's recorded launches on the CPU (faster than launching from Python there; measured in
  docs/performance.md, section 4).
"""

from __future__ import annotations

import copy
from typing import Any, Iterable, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.backend.field_views import FieldViews
from embodichain_core.sim.backend.env_rows import np_ids
from embodichain_core.sim.backend.interface import DERIVED_FIELDS, STATE_FIELDS, SimCapabilities
from embodichain_core.sim.backend.warp_device import (
    StepGraphs,
    host_arrays_for,
    init_warp,
    resolve_device,
    torch_device,
)
from embodichain_core.sim.backend.warp_failures import WarpFailures
from embodichain_core.sim.backend.warp_model import WarpModelFields
from embodichain_core.sim.backend.warp_views import flat_rows

_AUTORESET = int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
#: :meth:`WarpSim.advance` checks MuJoCo Warp's contact-overflow flags (a host read) every this many calls.
CONTACT_CHECK_PERIOD = 64
#: Outputs :meth:`WarpSim.forward` computes for the envs it was asked for only.
_ACTUATION = ("qfrc_actuator", "actuator_force")
#: State (and acceleration-level outputs) a subset step puts back for the envs outside the subset.
_KEPT = "qpos qvel act qacc_warmstart time history plastic qacc qfrc_actuator actuator_force cfrc_ext".split()


class WarpSim(WarpFailures, FieldViews):
    """``num_envs`` MuJoCo Warp worlds of one compiled model.

    Args:
        model: the compiled scene (the host template; MuJoCo's own autoreset stays off).
        num_envs: worlds.
        substeps: MuJoCo steps per :meth:`step`.
        device: ``"cpu"`` (Warp's CPU device), ``"cuda"`` or ``"cuda:N"``.
        nconmax, njmax: contacts and constraint rows per world (default: from the model;
            kept as attributes).
        host_arrays: numpy views of the state as ``sim.arrays`` (``None``: on Warp's CPU
            device, unless built inside
            :func:`~embodichain_core.sim.backend.warp_device.cpu_device_route`; ``False``:
            the torch views only, as on a GPU).

    Raises:
        ConfigError: a device or model feature MuJoCo Warp does not support.
        ValueError: ``host_arrays=True`` on a GPU.
    """

    #: :meth:`reset` takes no saved state row (the scene's default-row fast path is off).
    restores_state_rows = False

    def __init__(
        self,
        model: mujoco.MjModel,
        num_envs: int,
        substeps: int = 1,
        device: str = "cpu",
        nconmax: Optional[int] = None,
        njmax: Optional[int] = None,
        host_arrays: Optional[bool] = None,
    ):
        self.wp = init_warp()
        import mujoco_warp

        self.mjw = mujoco_warp
        self.model = model
        self.num_envs = int(num_envs)
        self.substeps = int(substeps)
        self.wp_device = resolve_device(self.wp, device)
        self.device = torch_device(self.wp_device)
        self.dtype = torch.float32
        on_cpu = self.wp_device == "cpu"
        self.capabilities = SimCapabilities(
            subset_step=False,
            host_arrays=host_arrays_for(self.wp_device, host_arrays),
            float64=False,
            deterministic=on_cpu,
        )
        self.graphs = StepGraphs(self.wp, self.wp_device)
        self._make(nconmax, njmax)
        self.fields = WarpModelFields(self.model, self.wp, self.mjw, self.wp_model, self.wp_data, self.graphs)
        """The model fields' per-env values and the constants due (:mod:`.warp_model`)."""
        self._dirty = np.zeros(self.num_envs, dtype=bool)
        self._maybe_dirty = False
        self._pending_failed: list[int] = []
        self._warned_overflow = False
        self._advances = 0
        self.reset(None)

    # -- construction ------------------------------------------------------------------------------
    def _make(self, nconmax: Optional[int], njmax: Optional[int]) -> None:
        mjm = self.host_model = _warp_ready(self.model)
        """The host model MuJoCo Warp was given (``model`` with autoreset cleared)."""
        data = mujoco.MjData(mjm)
        mujoco.mj_forward(mjm, data)
        self.nconmax = nconmax = int(nconmax or max(48, 2 * data.ncon + 2 * mjm.nbody))
        self.njmax = njmax = int(njmax or max(64, 4 * nconmax + 2 * mjm.nv + 6 * mjm.neq))
        with self.wp.ScopedDevice(self.wp_device):
            try:
                self.wp_model = self.mjw.put_model(mjm)
            except NotImplementedError as err:
                raise ConfigError(
                    "sim_cfg.backend",
                    f"backend 'warp' cannot simulate this scene: {err} "
                    "(use backend 'mujoco_batch', or change sim_cfg.physics_config)",
                ) from err
            self.wp_data = self.mjw.put_data(mjm, data, nworld=self.num_envs, nconmax=nconmax, njmax=njmax)
            self._reset_mask = self.wp.zeros(self.num_envs, dtype=bool)
        self._mask = self.wp.to_torch(self._reset_mask)
        self._views: dict[str, torch.Tensor] = {}
        for name in STATE_FIELDS + DERIVED_FIELDS:
            array = getattr(self.wp_data, name, None)
            if array is not None:
                self._views[name] = flat_rows(self.wp.to_torch(array), self.num_envs)
        self._kept = {
            n: self.wp.to_torch(getattr(self.wp_data, n)) for n in _KEPT if getattr(self.wp_data, n, None) is not None
        }
        self._overflow = self.wp.to_torch(self.wp_data.overflow)
        if self.capabilities.host_arrays:  # else no ``arrays``: the state is reached through its tensors
            self.arrays: dict[str, np.ndarray] = {n: getattr(self.wp_data, n).numpy() for n in STATE_FIELDS}

    def mark_dirty(self, env_ids: Any = None) -> None:
        """Note a direct state write; derived views are refreshed before the next read."""
        self._dirty[np_ids(env_ids, self.num_envs)] = True
        self._maybe_dirty = True

    def _forward_dirty(self) -> None:
        if self._dirty.any():
            self.forward(None)
        self._maybe_dirty = False

    # -- stepping ----------------------------------------------------------------------------------
    def _refresh(self) -> None:
        """Position and velocity stages of every world (sensors included), from its state."""
        self.mjw.step1(self.wp_model, self.wp_data)

    def _advance(self, n: int) -> None:
        for _ in range(n):
            self.mjw.step(self.wp_model, self.wp_data)
        self._refresh()

    def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
        """Advance ``env_ids`` (``None``: every env) by ``nstep`` physics steps; return the envs
        that diverged (non-finite state, or constraint rows over ``njmax``).

        A subset steps every world and then restores the others' state (and refreshes
        their derived views): slow, use it off the hot path.
        """
        self.flush_const()
        n = int(nstep) * self.substeps
        if env_ids is None:
            failed = self._step_all(n)
            if self._pending_failed:
                failed, self._pending_failed = sorted(set(failed) | set(self._pending_failed)), []
            return failed
        rows = np.unique(np_ids(env_ids, self.num_envs))
        if not len(rows):
            return []
        others = np.setdiff1d(np.arange(self.num_envs), rows)
        idx = torch.as_tensor(others, device=self.device)
        saved = {name: t[idx].clone() for name, t in self._kept.items()}
        before, subset = set(self._pending_failed), set(rows.tolist())
        failed = [i for i in self._step_all(n) if i in subset]
        for name, values in saved.items():
            self._kept[name][idx] = values
        self.graphs.run("refresh", self._refresh)
        failed = sorted(set(failed) | (set(self._pending_failed) - before))
        self._pending_failed = sorted(before | set(failed))
        return failed

    def _step_all(self, n: int) -> list[int]:
        self.graphs.run(("step", n), lambda: self._advance(n))
        self._dirty[:] = False
        self._maybe_dirty = False
        return self._failed()

    def advance(self, nstep: int = 1) -> torch.Tensor:
        """Step every env (as ``step(nstep)``); the ``(num_envs,)`` bool mask of the envs that
        diverged, computed on the device without a host wait (:meth:`error` says why)."""
        self.flush_const()
        n = int(nstep) * self.substeps
        self.graphs.run(("step", n), lambda: self._advance(n))
        self._dirty[:] = False
        self._maybe_dirty = False
        failed = self._failed_mask()
        if self._pending_failed:  # failures of a subset step (off the hot path)
            failed[torch.as_tensor(self._pending_failed, device=self.device)] = True
            self._pending_failed = []
        self._advances += 1
        if self._advances % CONTACT_CHECK_PERIOD == 0:
            self._warn_contact_overflow()
        return failed

    def forward(self, env_ids: Any = None) -> None:
        """Recompute derived views: positions and velocities of every world (MuJoCo Warp has
        no subset), and the actuator forces of ``env_ids`` (default: the envs written since
        the last step; the others keep those of their last step, as on ``mujoco_batch``)."""
        self.flush_const()
        rows = np.flatnonzero(self._dirty) if env_ids is None else np_ids(env_ids, self.num_envs)
        if env_ids is None and not len(rows):
            rows = np.arange(self.num_envs)
        saved = {n: self._kept[n].clone() for n in _ACTUATION if n in self._kept}
        self.graphs.run("forward", self._refresh_with_actuation)
        if len(rows) < self.num_envs:
            others = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
            others[torch.as_tensor(rows, dtype=torch.long, device=self.device)] = False
            for name, values in saved.items():  # no boolean indexing: no wait for the device
                view = self._kept[name]
                view.copy_(torch.where(others[:, None], values, view))
        self._dirty[:] = False
        self._maybe_dirty = False

    def _refresh_with_actuation(self) -> None:
        self._refresh()
        self.mjw.fwd_actuation(self.wp_model, self.wp_data)

    def reset(self, env_ids: Any = None, state: Optional[np.ndarray] = None) -> None:
        """Model defaults for ``env_ids`` (``reset_data`` with a world mask; no forward);
        their failures not reported yet are dropped.

        Raises:
            ValueError: a saved ``state`` row: MuJoCo Warp keeps no state rows, so this
                backend has no ``restores_state_rows`` (the scene resets entities instead).
        """
        if state is not None:
            raise ValueError(
                "WarpSim.reset(state=...): backend 'warp' does not restore saved state rows "
                "(restores_state_rows is False); reset without state and write the entities' "
                "initial state instead"
            )
        rows = np_ids(env_ids, self.num_envs)
        self._mask.zero_()
        self._mask[torch.as_tensor(rows, device=self.device)] = True
        self.graphs.run("reset", lambda: self.mjw.reset_data(self.wp_model, self.wp_data, self._reset_mask))
        self.mark_dirty(rows)
        reset = set(rows.tolist())
        self._pending_failed = [i for i in self._pending_failed if i not in reset]

    # -- model fields: the interface's methods, answered by :attr:`fields` ------------------------
    def declare_per_env(self, names: Iterable[str]) -> None:
        """Expand ``names`` per world now, before graph capture (:class:`WarpModelFields`)."""
        self.fields.declare_per_env(names)

    def is_per_env(self, name: str) -> bool:
        """Whether ``name`` holds per-env values."""
        return self.fields.is_per_env(name)

    def model_field(self, name: str) -> np.ndarray:
        """Read-only ``(num_envs, ...)`` values of model field ``name``."""
        return self.fields.model_field(name)

    def model_tensor(self, name: str) -> torch.Tensor:
        """``(num_envs, ...)`` values of model field ``name`` on the sim's device (MuJoCo Warp's
        own array where per env: no host copy)."""
        return self.fields.model_tensor(name, self.device)

    def set_model_field(self, name: str, env_ids: Any, index: Any, values: Any, set_const: bool = True) -> None:
        """Write ``values`` into ``name[index]`` of each env (ConfigError where MuJoCo Warp cannot)."""
        self.fields.set_model_field(name, env_ids, index, values, set_const)

    def set_body_masses(self, env_ids: Any, bodies: Any, mass: Any) -> None:
        """Masses ``(n, k)`` of ``bodies``; their inertias scale along (one recompute)."""
        self.fields.set_body_masses(env_ids, bodies, mass)

    def mark_const_dirty(self, env_ids: Any = None, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Schedule the recompute of the constants of ``fields`` (all groups if unknown)."""
        self.fields.mark_const_dirty(fields)

    def flush_const(self) -> None:
        """Run the scheduled constant recomputes now (over every world)."""
        self.fields.flush_const()

    def get_model(self, env_id: int, model: Optional[mujoco.MjModel] = None) -> mujoco.MjModel:
        """Env ``env_id``'s model on the host: the template with its per-env rows."""
        return self.fields.get_model(env_id, model)

    def get_data(self, env_id: int, data: Optional[mujoco.MjData] = None) -> mujoco.MjData:
        """Env ``env_id``'s ``MjData`` on the host (float64 copy; derived fields current)."""
        self.flush_const()
        if self._maybe_dirty:
            self._forward_dirty()
        data = mujoco.MjData(self.host_model) if data is None else data
        self.mjw.get_data_into(data, self.host_model, self.wp_data, int(env_id))
        if data.ncon:  # MuJoCo Warp fills contact.geom only; contact sensors read geom1/geom2
            data.contact.geom1[:] = data.contact.geom[:, 0]
            data.contact.geom2[:] = data.contact.geom[:, 1]
        return data


def _warp_ready(model: mujoco.MjModel) -> mujoco.MjModel:
    """A copy MuJoCo Warp accepts: its autoreset flag cleared (MuJoCo Warp never autoresets;
    divergence is reported by :meth:`WarpSim.step`)."""
    mjm = copy.copy(model)
    mjm.opt.disableflags &= ~_AUTORESET
    return mjm
