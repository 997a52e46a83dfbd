"""The simulation interface: what envs, entities, managers and plugins may call on ``env.sim``.

A backend simulates ``num_envs`` copies of one compiled ``MjModel``. Today's backend is
:class:`~embodichain_core.sim.backend.batch_sim.BatchSim` (``mujoco.batch``, CPU,
float64); a GPU backend (MuJoCo Warp, float32) implements the same protocol. Nothing
outside ``sim/backend/`` touches the object underneath (plugins never import
``mujoco.batch``).

Conventions:

* **Views are persistent.** ``sim.qpos`` (any name of :data:`STATE_FIELDS` or
  :data:`DERIVED_FIELDS`, also ``sim.view(name)``) is the same tensor for the backend's
  lifetime, on ``sim.device`` in ``sim.dtype``, leading dim ``num_envs``. Write state in
  place (``sim.qpos[ids, cols] = v``, values in ``sim.dtype``), never rebind it.
  ``sim.tensors`` maps the state fields' names to their views. ``sim.arrays`` holds numpy
  views of the same memory where ``capabilities.host_arrays`` (the cheap way to write a
  few values of a few envs); a backend without them has no ``arrays``. Entities pick one
  of the two once (:mod:`~embodichain_core.sim.backend.state_route`).
* **Forward is lazy.** After writing state directly, call :meth:`mark_dirty`; derived
  views are recomputed for those envs before they are next read or stepped.
* **Model fields.** :meth:`model_field` reads ``(num_envs, ...)`` values (shared fields
  broadcast, read-only); :meth:`set_model_field` writes per-env values. A write of a field
  MuJoCo derives constants from (mass, inertia, positions of lights...) schedules the
  recompute for those envs, run once before the next step or forward.
* **Env ids** are ``None`` (every env), a list, an int64 array, a long tensor or a bool mask.
* **Divergence is reported, never swallowed.** :meth:`step` returns the envs whose
  simulation failed or went non-finite; they keep a state the env loop resets.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Optional, Protocol, runtime_checkable

import mujoco
import numpy as np
import torch

STATE_FIELDS = ("qpos", "qvel", "act", "ctrl", "qfrc_applied", "xfrc_applied", "mocap_pos", "mocap_quat", "eq_active")
"""Writable state views, ``(num_envs, ...)`` (``xfrc_applied`` ``(N, nbody, 6)``, quaternions wxyz)."""
DERIVED_FIELDS = (
    "xpos",
    "xquat",
    "xmat",
    "cvel",
    "site_xpos",
    "site_xmat",
    "qfrc_actuator",
    "actuator_force",
    "cfrc_ext",
    "qacc",
    "sensordata",
    "light_xpos",
    "light_xdir",
    "cam_xpos",
    "cam_xmat",
    "geom_xpos",
    "geom_xmat",
    "ncon",
)
"""Read-only views computed from the state (current for every env that is not dirty)."""


@dataclass(frozen=True)
class SimCapabilities:
    """What a backend does natively (the interface works either way, at some cost).

    Attributes:
        subset_step: :meth:`SimBackend.step` of a subset runs only those envs (without
            it a backend steps every env with the others' state saved and restored).
        host_arrays: ``sim.arrays`` are zero-copy numpy views of the state (without it the
            backend has no ``arrays``: its state is device memory).
        float64: state and views are float64 (else float32).
        deterministic: the same inputs give bit-identical results at any thread count.
    """

    subset_step: bool
    host_arrays: bool
    float64: bool
    deterministic: bool


@runtime_checkable
class SimBackend(Protocol):
    """``num_envs`` simulations of one model behind persistent tensor views (see module doc).

    Attributes:
        model: the host ``MjModel`` template (ids, names, sizes, defaults).
        num_envs: number of simulations, the leading dim of every view.
        substeps: MuJoCo steps per physics step (``physics_dt / timestep``).
        device, dtype: of every tensor view.
        capabilities: see :class:`SimCapabilities`.
        arrays: (only where ``capabilities.host_arrays``) numpy views of :data:`STATE_FIELDS`
            by name, persistent like the tensor views (read-only mapping, the arrays
            themselves are writable).
        restores_state_rows: (optional, ``False`` when absent) whether :meth:`reset` takes a
            saved state row (``state=``; see :mod:`embodichain_core.sim.scene_defaults`).
    """

    model: mujoco.MjModel
    num_envs: int
    substeps: int
    device: torch.device
    dtype: torch.dtype
    capabilities: SimCapabilities

    @property
    def tensors(self) -> Mapping[str, torch.Tensor]:
        """The torch views of :data:`STATE_FIELDS`, by name (the same tensors as ``sim.<field>``)."""
        ...

    # -- stepping and state -------------------------------------------------------------------
    def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
        """Advance ``env_ids`` (every env: ``None``) by ``nstep`` physics steps; the others
        keep their state. Returns the envs that diverged in this call. Failures of a subset
        step or of a forward are reported again by the next step of every env (the env
        loop truncates and resets them there) unless the env was reset in between."""
        ...

    def advance(self, nstep: int = 1) -> torch.Tensor:
        """Advance every env by ``nstep`` physics steps, as ``step(nstep)``; return a
        ``(num_envs,)`` bool tensor on ``device``, True where the env diverged (the env loop's
        call: on a GPU it does not wait for the device)."""
        ...

    def forward(self, env_ids: Any = None) -> None:
        """Make the derived views of (at least) ``env_ids`` current."""
        ...

    def reset(self, env_ids: Any = None, state: Optional[np.ndarray] = None) -> None:
        """State of ``env_ids`` to the model defaults (no forward: they are marked dirty);
        their failures not reported yet are dropped. ``state``: a saved ``(nstate,)`` row
        written into them afterwards, for backends with ``restores_state_rows`` (others
        raise ``ValueError``)."""
        ...

    def mark_dirty(self, env_ids: Any = None) -> None:
        """Declare a direct state write of ``env_ids``; forward runs lazily."""
        ...

    def view(self, name: str) -> torch.Tensor:
        """The persistent view of a state or derived field (same as ``sim.<name>``)."""
        ...

    def error(self, env_id: int) -> str:
        """The message of env ``env_id``'s last failure ('' if none)."""
        ...

    # -- model fields -------------------------------------------------------------------------
    def declare_per_env(self, names: Iterable[str]) -> None:
        """Setup: model fields that will get per-env values (a GPU backend allocates them
        before capturing its graphs; later writes of other fields may be slow)."""
        ...

    def is_per_env(self, name: str) -> bool:
        """Whether model field ``name`` currently holds per-env values."""
        ...

    def model_field(self, name: str) -> np.ndarray:
        """``(num_envs, ...)`` read-only values of a model field."""
        ...

    def model_tensor(self, name: str) -> torch.Tensor:
        """``(num_envs, ...)`` values of a model field as a tensor on :attr:`device`, without
        a copy through the host where the backend holds them on the device (read it; write
        with :meth:`set_model_field`)."""
        ...

    def set_model_field(self, name: str, env_ids: Any, index: Any, values: Any, set_const: bool = True) -> None:
        """Write ``values`` into ``field[index]`` of each env (a list ``index`` selects several
        elements: values ``(n, k, ...)``). ``set_const=False``: the caller writes the derived
        constants itself."""
        ...

    def set_body_masses(self, env_ids: Any, bodies: Any, mass: Any) -> None:
        """Masses ``(n, k)`` of ``bodies``; their inertias scale along (one recompute)."""
        ...

    def mark_const_dirty(self, env_ids: Any = None, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Declare constant inputs of ``env_ids`` written (``(name, index)`` pairs, if known)."""
        ...

    def flush_const(self) -> None:
        """Run the scheduled constant recomputes now (otherwise before the next step/forward)."""
        ...

    # -- host copies ---------------------------------------------------------------------------
    def get_model(self, env_id: int, model: Optional[mujoco.MjModel] = None) -> mujoco.MjModel:
        """Env ``env_id``'s model on the host (for rendering or any ``mj_`` function)."""
        ...

    def get_data(self, env_id: int, data: Optional[mujoco.MjData] = None) -> mujoco.MjData:
        """Env ``env_id``'s ``MjData`` on the host, derived fields current."""
        ...
