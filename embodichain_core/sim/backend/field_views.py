"""Field access by name, shared by the backends: ``sim.qpos``, ``sim.view("xpos")``.

A backend keeps its persistent views in ``self._views`` (name -> tensor) and sets
``self._maybe_dirty`` when envs await their lazy forward; reading a derived field runs
that forward first (:meth:`_forward_dirty`), reading a state field does not.
"""

from __future__ import annotations

import torch

from embodichain_core.sim.backend.interface import STATE_FIELDS


class FieldViews:
    """Mixin: ``sim.<field>`` and :meth:`view` over the backend's persistent views."""

    _views: dict[str, torch.Tensor]
    _maybe_dirty: bool

    def _forward_dirty(self) -> None:
        """Run the lazy forward of the dirty envs (each backend implements it)."""
        raise NotImplementedError(f"{type(self).__name__} must implement _forward_dirty")

    def __getattr__(self, name: str) -> torch.Tensor:
        views = self.__dict__.get("_views")
        if views is not None and name in views:
            if self._maybe_dirty and name not in STATE_FIELDS:
                self._forward_dirty()
            return views[name]
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    def view(self, name: str) -> torch.Tensor:
        """The persistent view of a state or derived field (same as ``sim.<name>``)."""
        return self.__getattr__(name)
