"""The base of the standard action terms: params with defaults, the active joints, their limits."""

from __future__ import annotations

from typing import Any

import torch

from embodichain_core.managers.functor import ActionTerm


class _Term(ActionTerm):
    """Params with defaults (``defaults``); unknown params are errors at construction."""

    defaults: dict[str, Any] = {"scale": 1.0}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        unknown = [k for k in cfg.params if k not in self.defaults]
        if unknown:
            raise ValueError(
                f"params.{unknown[0]}: unknown parameter of {type(self).__name__} (parameters: {sorted(self.defaults)})"
            )
        self.params = {**self.defaults, **cfg.params}
        scale = self.params.get("scale", 1.0)
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or scale == 0:
            raise ValueError(f"params.scale: must be a non-zero number, got {scale!r}")
        self.scale = float(scale)
        self.robot = env.robot
        self.joints = torch.as_tensor(env.active_joint_ids, dtype=torch.long)
        self._joints = self.joints.to(env.device, copy=True)  # the same, on the env's device
        self._limits: torch.Tensor | None = None

    def limits(self) -> torch.Tensor:
        """(N, n_active, 2) position limits of the active joints, on the env's device; read
        once and again after every reset (reset events may randomize them)."""
        if self._limits is None:
            self._limits = self.robot.get_qpos_limits()[:, self._joints]
        return self._limits

    def reset(self, env_ids: Any = None) -> None:
        """Read the joint limits again at the next :meth:`limits` (after the reset events)."""
        self._limits = None

    def _columns(self, key: str = "joint_ids") -> torch.Tensor:
        ids = self.params.get(key)
        n = len(self.joints)
        cols = torch.arange(n) if ids is None else torch.as_tensor(ids, dtype=torch.long).reshape(-1)
        if len(cols) and (cols.min() < 0 or cols.max() >= n):
            raise ValueError(f"params.{key}: indices into the {n} active joints, got {cols.tolist()}")
        return cols

    def _range(self, default: tuple) -> tuple[float, float]:
        rng = self.params.get("range", default)
        if not isinstance(rng, (list, tuple)) or len(rng) != 2 or float(rng[0]) >= float(rng[1]):
            raise ValueError(f"params.range: expected [low, high] with low < high, got {rng!r}")
        return float(rng[0]), float(rng[1])
