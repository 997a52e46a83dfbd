"""Field access by name, shared by the backends: ``sim.qpos``, ``sim.view("xpos")``.

:class:`FieldViews` is the one base class of both backends: its behaviour (the lookup)
is the same for each, and each backend supplies what it reads: the persistent views in
``self._views`` (name -> tensor, set in its constructor), ``self._maybe_dirty`` (set
while envs await their lazy forward) and the forward itself (:meth:`_forward_dirty`,
abstract). Reading a derived field runs that forward first; reading a state field does not.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import torch

from embodichain_core.sim.backend.interface import STATE_FIELDS


class FieldViews(ABC):
    """Base of the backends: ``sim.<field>`` and :meth:`view` over their persistent views."""

    _views: dict[str, torch.Tensor]
    _maybe_dirty: bool

    @abstractmethod
    def _forward_dirty(self) -> None:
        """Run the lazy forward of the dirty envs and clear ``_maybe_dirty``."""

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
