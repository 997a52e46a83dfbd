"""Joint position action terms: absolute, delta, (de)normalized joint position targets."""

from __future__ import annotations

from typing import Any

import torch

from embodichain_functors.actions.base import _Term


class DeltaQposTerm(_Term):
    """Joint position targets = current positions of the active joints + ``scale * action``.

    Works with any subset of active joints. The policy range is
    ``[-action_limit, action_limit]`` per joint; targets are clipped to the joint
    limits (``clip=True``).

    Params: ``scale`` (1.0), ``action_limit`` (1.0), ``clip`` (True).

    Example:
        ``{"func": "DeltaQposTerm", "params": {"scale": 0.1}}``
    """

    input_key = "qpos"
    defaults = {"scale": 1.0, "action_limit": 1.0, "clip": True}

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        limit = float(self.params["action_limit"])
        return torch.full((self.action_dim,), -limit), torch.full((self.action_dim,), limit)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        target = self.robot.get_qpos()[:, self._joints] + self.scale * torch.as_tensor(action, dtype=torch.float32)
        if self.params["clip"]:
            lim = self.limits()
            target = torch.maximum(torch.minimum(target, lim[..., 1]), lim[..., 0])
        return target


class QposTerm(_Term):
    """Joint position targets = ``scale * action`` (policy range: the joint limits / scale).

    Params: ``scale`` (1.0).

    Example:
        ``{"func": "QposTerm", "params": {"scale": 1.0}}``
    """

    input_key = "qpos"

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0] / self.scale
        return lim.min(-1).values, lim.max(-1).values

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return self.scale * torch.as_tensor(action, dtype=torch.float32)

    def action_from_qpos(self, qpos: torch.Tensor) -> torch.Tensor:
        return torch.as_tensor(qpos, dtype=torch.float32) / self.scale


class QposDenormalizedTerm(_Term):
    """Map ``scale * action`` from ``range`` to the joint limits for ``joint_ids``.

    Other active joints take ``scale * action`` as is.

    Params: ``scale`` (1.0), ``joint_ids`` (indices into the active joints; all), ``range`` ([-1, 1]).

    Example:
        ``{"func": "QposDenormalizedTerm", "params": {"range": [-1, 1]}}``
    """

    input_key = "qpos"
    defaults = {"scale": 1.0, "joint_ids": None, "range": (-1.0, 1.0)}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.cols, self.range = self._columns(), self._range((-1.0, 1.0))

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0] / self.scale
        low, high = lim.min(-1).values, lim.max(-1).values
        low[self.cols], high[self.cols] = self.range[0] / self.scale, self.range[1] / self.scale
        return low, high

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = self.scale * torch.as_tensor(action, dtype=torch.float32)
        lim = self.limits()[:, self.cols]
        r0, r1 = self.range
        out[:, self.cols] = lim[..., 0] + (out[:, self.cols] - r0) / (r1 - r0) * (lim[..., 1] - lim[..., 0])
        return out

    def action_from_qpos(self, qpos: torch.Tensor) -> torch.Tensor:
        out = torch.as_tensor(qpos, dtype=torch.float32).clone()
        lim = self.limits()[:, self.cols].to(out)
        r0, r1 = self.range
        span = (lim[..., 1] - lim[..., 0]).clamp_min(1e-12)
        out[:, self.cols] = r0 + (out[:, self.cols] - lim[..., 0]) / span * (r1 - r0)
        return out / self.scale


class QposNormalizedTerm(_Term):
    """Map joint positions from the joint limits to ``range`` for ``joint_ids`` (usually ``mode="post"``).

    Params: ``joint_ids`` (indices into the active joints; all), ``range`` ([0, 1]).

    Example:
        ``{"func": "QposNormalizedTerm", "mode": "post", "params": {"range": [0, 1]}}``
    """

    input_key = "qpos"
    defaults = {"joint_ids": None, "range": (0.0, 1.0)}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.cols, self.range = self._columns(), self._range((0.0, 1.0))

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0]
        return lim[:, 0], lim[:, 1]

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = torch.as_tensor(action, dtype=torch.float32).clone()
        lim = self.limits()[:, self.cols]
        r0, r1 = self.range
        span = (lim[..., 1] - lim[..., 0]).clamp_min(1e-12)
        out[:, self.cols] = r0 + (out[:, self.cols] - lim[..., 0]) / span * (r1 - r0)
        return out
