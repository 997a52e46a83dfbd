"""The scene's default state row: what a reset leaves in an env's state, saved once.

A reset puts an env's whole state row back to the model's defaults, then every
entity writes its initial state into it (robot joints and their targets, object
poses at rest, ...). The result is the same row every time, so after the first
reset of the slow kind :class:`DefaultRows` keeps a copy and later resets restore
it with one write (``sim.reset(ids, state=row)``), skipping the entities whose reset
only writes state (``Entity.state_only_reset``). The others (lights, sensors, ...)
still run theirs. :meth:`embodichain_core.sim.scene.Scene.reset` makes that choice.

The row is used only while it stays right:

* the backend restores rows (``restores_state_rows``) and no model field a reset
  reads (:data:`RESET_MODEL_FIELDS`) holds per-env values;
* those model fields and what every state-only entity declares its reset reads
  (``Entity.initial_state()``) are unchanged since the row was saved (compared by
  value on every use, so an in-place edit counts too); anything
  else drops the row, and the slow reset runs and saves a new one.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import torch

#: Model fields ``mj_resetData`` reads into the state row.
RESET_MODEL_FIELDS = ("qpos0", "body_pos", "body_quat", "eq_active0")


class DefaultRows:
    """The saved default state row of a scene (see the module doc).

    Args:
        scene: the scene (its ``sim``, ``model`` and ``entities`` once built).
    """

    def __init__(self, scene: Any):
        self._scene = scene
        self._row: Optional[np.ndarray] = None
        self._fingerprint: Optional[np.ndarray] = None

    def row(self) -> Optional[np.ndarray]:
        """The saved row when it may be used now, else ``None`` (and the row is dropped)."""
        if self._row is None or self._fingerprint is None:  # set together by capture()
            return None
        if not self._usable() or not np.array_equal(self._inputs(), self._fingerprint):
            self._row = self._fingerprint = None
        return self._row

    def capture(self, env_ids: torch.Tensor) -> None:
        """Save the row of ``env_ids[0]``, just reset the slow way (model defaults, then
        every entity), when rows may be saved at all."""
        if len(env_ids) and self._usable():
            self._row = np.array(self._scene.sim.state[int(env_ids[0])], dtype=np.float64)
            self._fingerprint = self._inputs()

    def _usable(self) -> bool:
        sim = self._scene.sim
        if not getattr(sim, "restores_state_rows", False):
            return False
        return not any(sim.is_per_env(name) for name in RESET_MODEL_FIELDS)

    def _inputs(self) -> np.ndarray:
        """Everything the row was derived from, as one flat array (compared on each use)."""
        model = self._scene.model
        parts = [model.qpos0, model.body_pos.ravel(), model.body_quat.ravel(), model.eq_active0.astype(np.float64)]
        for entity in self._scene.entities.values():
            parts += [np.asarray(a, dtype=np.float64).ravel() for a in entity.initial_state()]
        return np.concatenate(parts)
