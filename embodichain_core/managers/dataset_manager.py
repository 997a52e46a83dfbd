"""Dataset manager: drives recorder functors at fixed points of the env loop.

* after every step: ``record_step(obs, action, reward, terminated, truncated, info)``;
* before a reset, for the envs whose episode ended: commit (``functor(env, env_ids)``)
  the successful ones (all with ``save_failed_episodes``) and ``discard`` the rest;
* on ``close()``: ``finalize()``, which never commits a partial episode.
"""

from __future__ import annotations

from typing import Any, Optional

import torch

from embodichain_core.config.checks import describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import DatasetFunctorCfg
from embodichain_core.managers.manager_base import ValidatedFunctor, ManagerBase, tag_functor_error


class DatasetManager(ManagerBase[DatasetFunctorCfg]):
    """Runs dataset recorder functors."""

    section = "dataset"
    kind = "dataset"
    cfg_type = DatasetFunctorCfg
    min_argc = 2
    modes = ("save",)

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """A known ``mode``; ``save_failed_episodes`` true or false."""
        cls.check_mode(checked.cfg.mode, checked.path)
        if not isinstance(checked.cfg.save_failed_episodes, bool):
            raise ConfigError(
                join_path(checked.path, "save_failed_episodes"),
                f"expected true/false, got {describe(checked.cfg.save_failed_episodes)}",
            )

    def __init__(self, cfg: Any, env: Any, path: str | None = None):
        super().__init__(cfg, env, path)
        self._finalized: Optional[list] = None
        self.committed_episodes = 0  # env episodes handed to the recorders for saving

    @property
    def save_failed_episodes(self) -> bool:
        return any(e.cfg.save_failed_episodes for e in self.entries.values())

    def record_step(
        self, obs: Any, action: Any, reward: torch.Tensor, terminated: torch.Tensor, truncated: torch.Tensor, info: dict
    ) -> None:
        for e in self.entries.values():
            if hasattr(e.func, "record_step"):
                try:
                    e.func.record_step(obs, action, reward, terminated, truncated, info)
                except Exception as err:
                    tag_functor_error(err, e.path, e.func)
                    raise

    def record_reset(self, obs: Any, env_ids: torch.Tensor) -> None:
        for e in self.entries.values():
            if hasattr(e.func, "record_reset"):
                try:
                    e.func.record_reset(obs, env_ids)
                except Exception as err:
                    tag_functor_error(err, e.path, e.func)
                    raise

    def commit(self, env_ids: torch.Tensor) -> None:
        """Save the finished episodes of ``env_ids``."""
        if len(env_ids) == 0:
            return
        for e in self.entries.values():
            e(self._env, env_ids)
        self.committed_episodes += len(env_ids)

    def discard(self, env_ids: torch.Tensor) -> None:
        if len(env_ids) == 0:
            return
        for e in self.entries.values():
            if hasattr(e.func, "discard"):
                e.func.discard(env_ids)

    def finalize(self) -> list:
        """Finalize every recorder once (idempotent), the others still when one fails.

        One failure is re-raised as it is, marked with the recorder's config path
        (:func:`~embodichain_core.managers.manager_base.functor_path_of`); several are
        raised together as one ``RuntimeError`` naming each recorder.
        """
        if self._finalized is not None:
            return self._finalized
        paths, errors = [], []
        for e in self.entries.values():
            try:
                if hasattr(e.func, "finalize"):
                    paths.append(e.func.finalize())
            except Exception as err:  # keep finalizing the others
                tag_functor_error(err, e.path, e.func)
                errors.append((e.path, err))
        self._finalized = paths
        if len(errors) == 1:
            raise errors[0][1]
        if errors:
            text = "; ".join(f"{path}: {type(err).__name__}: {err}" for path, err in errors)
            raise RuntimeError(f"dataset finalize failed in {len(errors)} recorders: {text}") from errors[0][1]
        return paths
