"""Per-env model and data for the sensors, written into reused buffers.

``BatchSim.get_model(i)`` and ``get_data(i)`` return new copies; the batch can also
write env ``i`` into an existing ``MjModel``/``MjData``, which is far cheaper (measured in
docs/performance.md, section 4).
"""

from __future__ import annotations

from typing import Any, Optional

import mujoco


class EnvReader:
    """Env ``i``'s model (with its per-env fields) and data, in buffers of ``scene``."""

    def __init__(self, scene: Any):
        self.scene = scene
        self._model: Optional[mujoco.MjModel] = None
        self._data: Optional[mujoco.MjData] = None

    def model(self, env_id: int) -> mujoco.MjModel:
        """The model env ``env_id`` runs on (valid until the next call)."""
        sim = self.scene.sim
        batch = getattr(sim, "batch", None)
        if batch is None:
            return sim.get_model(env_id)
        if self._model is None:
            self._model = batch.get_model(int(env_id))
            return self._model
        return batch.get_model(int(env_id), self._model)

    def data(self, env_id: int) -> mujoco.MjData:
        """Env ``env_id``'s MjData (valid until the next call)."""
        if self._data is None:
            self._data = mujoco.MjData(self.scene.model)
        return self.scene.sim.get_data(int(env_id), self._data)
