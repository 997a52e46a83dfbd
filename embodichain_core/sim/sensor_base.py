"""The contract every sensor type (a plugin) implements."""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.sim.entities.base import StateSlices


class BaseSensor:
    """A sensor of the scene, batched over envs.

    Lifecycle: constructed with ``(cfg, scene)`` before the scene is compiled;
    :meth:`build` adds what it needs to the spec (cameras, sites); :meth:`bind`
    runs once the batch exists; :meth:`update` computes the current data, which
    :meth:`get_data` returns as ``{name: tensor (N, ...)}``; :meth:`reset` runs on
    env resets.
    """

    state_only_reset = False
    """A sensor's reset clears its own buffers: a scene reset always runs it."""

    def __init__(self, cfg: Any, scene: Any):
        self.cfg = cfg
        self.scene = scene
        self.uid: str = cfg.uid

    def build(self, builder: Any) -> None:
        """Add spec elements before compile."""

    def bind(self) -> None:
        """Resolve ids after compile."""

    def update(self) -> None:
        """Refresh the data for the current simulation state."""

    def get_data(self) -> dict[str, torch.Tensor]:
        raise NotImplementedError(f"{type(self).__name__} must implement get_data()")

    def state_slices(self) -> StateSlices:
        """A sensor owns no simulation state columns."""
        return StateSlices()

    def initial_state(self) -> list[Any]:
        """Nothing of the saved default state row derives from a sensor."""
        return []

    def reset(self, env_ids: Any = None) -> None:
        """Clear per-env state of ``env_ids``."""

    def close(self) -> None:
        """Release renderer resources."""
