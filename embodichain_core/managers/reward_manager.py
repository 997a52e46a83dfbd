"""Reward manager: weighted reward terms ``f(env, obs, action, info, **params)``."""

from __future__ import annotations

from typing import Any, Optional

import torch

from embodichain_core.config.checks import check_number
from embodichain_core.config.errors import join_path
from embodichain_core.managers.cfg import RewardCfg
from embodichain_core.managers.manager_base import ValidatedFunctor, ManagerBase, tag_functor_error


class RewardManager(ManagerBase[RewardCfg]):
    """Sums weighted terms; a ``replace`` term sets the total (task reward included)."""

    section = "rewards"
    kind = "reward"
    cfg_type = RewardCfg
    min_argc = 4
    modes = ("add", "replace")

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """A known ``mode`` and a finite ``weight``."""
        cls.check_mode(checked.cfg.mode, checked.path)
        check_number(checked.cfg.weight, join_path(checked.path, "weight"))

    def compute(self, obs: Any, action: Any, info: dict, base: Optional[torch.Tensor]) -> tuple[torch.Tensor, dict]:
        """Return ``(total, {term: unweighted value})`` starting from the task's ``base``
        reward (``None``: zeros, the default task reward, added without a tensor op).

        One tensor op per term: the first term's product starts the total, the others
        are added in place with their weight as ``alpha``.
        """
        total = None if base is None else base.clone()
        terms: dict[str, torch.Tensor] = {}
        env = self._env
        n = env.num_envs
        for name, entry in self.entries.items():
            cfg = entry.cfg
            try:
                value = entry.func(env, obs, action, info, **cfg.params)
            except Exception as err:
                tag_functor_error(err, entry.path, entry.func)
                raise
            if type(value) is not torch.Tensor or value.dtype is not torch.float32:
                value = torch.as_tensor(value, dtype=torch.float32)
            if value.dim() == 0:
                value = value.expand(n)
            if value.shape != (n,):
                raise ValueError(f"{entry.path}: a reward term must have shape ({n},), got {tuple(value.shape)}")
            terms[name] = value
            if cfg.mode == "replace" or total is None:
                total = float(cfg.weight) * value  # a fresh tensor: the product
            else:
                total.add_(value, alpha=float(cfg.weight))  # total is this call's own tensor
        if total is None:  # no term at all: the default task reward
            total = torch.zeros(n, dtype=torch.float32, device=env.device)
        return total, terms

    def summary_rows(self) -> list[tuple[str, str, str]]:
        return [
            (e.cfg.mode, n, f"{getattr(e.cfg.func, '__name__', e.cfg.func)} (weight {e.cfg.weight:g})")
            for n, e in self.entries.items()
        ]
