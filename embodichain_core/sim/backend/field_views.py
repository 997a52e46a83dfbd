"""Field access by name, shared by the backends: ``sim.qpos``, ``sim.view("xpos")``.

:class:`FieldViews` is the one base class of both backends: its behaviour (the lookup)
is the same for each, and each backend supplies what it reads: the persistent views in
``self._views`` (name -> tensor, set in its constructor), ``self._maybe_dirty`` (set
while envs await their lazy forward) and the forward itself (:meth:`_forward_dirty`,
abstract). Reading a derived field runs that forward first; reading a state field does not.
:attr:`FieldViews.tensors` maps the state fields' names to their views (every backend); a
backend without host views of its state has no ``arrays`` and says so.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from types import MappingProxyType
from typing import Any, Mapping

import torch

from embodichain_core.sim.backend.interface import STATE_FIELDS


class FieldViews(ABC):
    """Base of the backends: ``sim.<field>`` and :meth:`view` over their persistent views."""

    _views: dict[str, torch.Tensor]
    _maybe_dirty: bool
    num_envs: int
    device: torch.device

    @abstractmethod
    def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
        """Advance ``env_ids`` by ``nstep`` physics steps; the envs that diverged."""

    def advance(self, nstep: int = 1) -> torch.Tensor:
        """Step every env by ``nstep`` (as :meth:`step`); return a ``(num_envs,)`` bool tensor
        on the sim's device, True where the env diverged. A backend on a GPU answers
        without waiting for the device; this default builds the mask from :meth:`step`'s ids."""
        failed = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
        ids = self.step(nstep)
        if ids:
            failed[torch.as_tensor(ids, dtype=torch.long, device=self.device)] = True
        return failed

    @abstractmethod
    def _forward_dirty(self) -> None:
        """Run the lazy forward of the dirty envs and clear ``_maybe_dirty``."""

    @property
    def tensors(self) -> Mapping[str, torch.Tensor]:
        """The torch views of the state fields (``STATE_FIELDS``), by name: the same tensors
        as ``sim.<field>`` (a read-only mapping; the tensors are writable)."""
        cached = self.__dict__.get("_tensors")
        if cached is None:
            cached = self.__dict__["_tensors"] = MappingProxyType(
                {n: self._views[n] for n in STATE_FIELDS if n in self._views}
            )
        return cached

    def __getattr__(self, name: str) -> torch.Tensor:
        views = self.__dict__.get("_views")
        if views is not None and name in views:
            if self._maybe_dirty and name not in STATE_FIELDS:
                self._forward_dirty()
            return views[name]
        if name == "arrays":
            raise AttributeError(
                f"{type(self).__name__} on {self.device} has no host arrays (capabilities.host_arrays "
                "is False: the state is device memory); use sim.tensors[name] or sim.<field>, "
                "or the entities' accessors"
            )
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    def view(self, name: str) -> torch.Tensor:
        """The persistent view of a state or derived field (same as ``sim.<name>``)."""
        return self.__getattr__(name)
