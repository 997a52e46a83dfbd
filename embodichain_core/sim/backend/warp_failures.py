"""Divergence of :class:`~embodichain_core.sim.backend.warp_sim.WarpSim` worlds, found on the device.

A world has failed when its state is non-finite or MuJoCo Warp ran out of constraint rows
(``njmax``); the failure is sticky until the world is reset. :meth:`WarpFailures._failed_mask`
is computed where the state is, so the env loop's step (``WarpSim.advance``) waits for no
device read; the reasons (:meth:`WarpFailures.error`) and the contact-overflow warning are
host reads, made on demand and every ``CONTACT_CHECK_PERIOD`` steps.
"""

from __future__ import annotations

import warnings
from typing import Any

import torch


class WarpFailures:
    """The failure checks of the warp backend (a mixin of ``WarpSim``, which sets
    ``_views``, ``_kept``, ``_overflow``, ``mjw`` and ``_warned_overflow``)."""

    _views: dict[str, torch.Tensor]
    _kept: dict[str, torch.Tensor]
    _overflow: torch.Tensor
    _warned_overflow: bool
    mjw: Any

    def _failed_mask(self) -> torch.Tensor:
        """Worlds with a non-finite state or a constraint overflow (sticky until reset)."""
        state = torch.cat([self._views["qpos"], self._views["qvel"], self._kept["act"]], dim=1)
        overflow = (self._overflow & int(self.mjw.OverflowType.NEFC)) != 0
        return ~torch.isfinite(state).all(dim=1) | overflow

    def _failed(self) -> list[int]:
        """:meth:`_failed_mask` as ids (a host read), with the contact-overflow warning."""
        ids = torch.nonzero(self._failed_mask()).flatten().tolist()
        self._warn_contact_overflow()
        return ids

    def _warn_contact_overflow(self) -> None:
        """Warn once when MuJoCo Warp dropped contacts (a host read of its overflow flags)."""
        kinds = self.mjw.OverflowType
        contacts = int(kinds.BROADPHASE | kinds.NARROWPHASE | kinds.CCD)
        if not self._warned_overflow and bool((self._overflow & contacts).any()):
            self._warned_overflow = True
            warnings.warn(
                "MuJoCo Warp's contact buffers overflowed; some contacts were dropped (raise WarpSim(nconmax=...))",
                RuntimeWarning,
                stacklevel=3,
            )

    def error(self, env_id: int) -> str:
        """Why env ``env_id`` failed ('' if it did not): read from its state now (the
        failure is sticky until the env is reset)."""
        i = int(env_id)
        state = torch.cat([self._views["qpos"][i], self._views["qvel"][i], self._kept["act"][i]])
        if not bool(torch.isfinite(state).all()):
            return "non-finite state"
        if bool(((self._overflow & int(self.mjw.OverflowType.NEFC)) != 0).any()):
            return "constraint rows over njmax (raise WarpSim(njmax=...))"
        return ""
