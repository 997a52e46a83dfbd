"""The simulation backend: stepping, state and per-env model fields behind one interface.

:class:`SimBackend` (:mod:`.interface`) is what envs, entities and plugins call;
:class:`BatchSim` (:mod:`.batch_sim`, ``mujoco.batch`` on the CPU) implements it, with
deferred derived constants (:mod:`.batch_constants`, closed form in :mod:`.free_body_const` /
:mod:`.free_body_geometry`) and env-id helpers (:mod:`.env_rows`: ``np_ids``,
``field_selector``) that plugins may use too.
"""

from embodichain_core.sim.backend.batch_sim import BatchSim
from embodichain_core.sim.backend.env_rows import field_selector, np_ids
from embodichain_core.sim.backend.interface import DERIVED_FIELDS, STATE_FIELDS, SimBackend, SimCapabilities

__all__ = ["BatchSim", "DERIVED_FIELDS", "STATE_FIELDS", "SimBackend", "SimCapabilities", "field_selector", "np_ids"]
