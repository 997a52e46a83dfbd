"""Action manager: ``pre`` terms turn the policy action into robot commands.

With several ``pre`` terms the flat policy action is split by the terms' dims in
declaration order and the commands are merged by ``input_key`` (``qpos``,
``qvel``, ``qf``), so velocity and effort terms really drive velocity and effort.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import ActionTermCfg
from embodichain_core.managers.functor import ActionTerm
from embodichain_core.managers.manager_base import ValidatedFunctor, ManagerBase


class ActionManager(ManagerBase[ActionTermCfg]):
    """Builds the action space from its ``pre`` terms and processes actions."""

    section = "actions"
    kind = "action"
    cfg_type = ActionTermCfg
    min_argc = None  # the params go to the term's constructor
    modes = ("pre", "post")

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """An ``ActionTerm`` class and a known ``mode``."""
        func = checked.func
        if not (isinstance(func, type) and issubclass(func, ActionTerm)):
            raise ConfigError(
                join_path(checked.path, "func"), f"an action term must be an ActionTerm class, got {func!r}"
            )
        cls.check_mode(checked.cfg.mode, checked.path)

    def terms(self, mode: str = "pre") -> dict[str, ActionTerm]:
        """The ``mode`` (``pre`` or ``post``) terms by name, in declaration order (one term by
        name: :meth:`get_functor`)."""
        return {n: e.func for n, e in self.entries.items() if e.cfg.mode == mode}

    def action_dim(self, mode: str = "pre") -> int:
        """Values per env the ``mode`` terms take (for ``pre``: the policy action's width)."""
        return sum(t.action_dim for t in self.terms(mode).values())

    def single_action_space(self) -> gym.spaces.Box | None:
        """The policy's per-env Box, or ``None`` without ``pre`` terms."""
        terms = self.terms("pre")
        if not terms:
            return None
        lows, highs = zip(*(t.action_bounds() for t in terms.values()))
        low = torch.cat([torch.as_tensor(x, dtype=torch.float32) for x in lows]).numpy()
        high = torch.cat([torch.as_tensor(x, dtype=torch.float32) for x in highs]).numpy()
        return gym.spaces.Box(low=low, high=high, dtype=np.float32)

    def process_action(self, action: Any, mode: str = "pre") -> Any:
        """Map the policy action to a command (tensor of qpos targets or a dict)."""
        terms = self.terms(mode)
        if not terms:
            return action
        if isinstance(action, dict):
            return self._process_dict(action, terms)
        action = torch.as_tensor(action, dtype=torch.float32)
        if len(terms) == 1:
            term = next(iter(terms.values()))
            command = term.process_action(action)
            if mode == "pre" and term.input_key != "qpos" and not isinstance(command, dict):
                # a bare tensor is applied as qpos: key velocity/effort commands by input_key
                return {term.input_key: command}
            return command
        return self._process_flat(action, terms)

    def _process_flat(self, action: torch.Tensor, terms: dict[str, ActionTerm]) -> dict:
        dims = [t.action_dim for t in terms.values()]
        if action.shape[-1] != sum(dims):
            raise ValueError(
                f"action has {action.shape[-1]} values per env; the action terms "
                f"{list(terms)} take {dims} (total {sum(dims)})"
            )
        out: dict[str, Any] = {}
        for term, chunk in zip(terms.values(), torch.split(action, dims, dim=-1)):
            _merge(out, term.input_key, term.process_action(chunk))
        return out

    def _process_dict(self, action: dict, terms: dict[str, ActionTerm]) -> dict:
        out: dict[str, Any] = {}
        for name, term in terms.items():
            key = name if name in action else term.input_key
            if key not in action:
                raise KeyError(f"action dict needs key {name!r} (or {term.input_key!r}); got {list(action)}")
            _merge(out, term.input_key, term.process_action(torch.as_tensor(action[key], dtype=torch.float32)))
        return out

    def action_names(self) -> list[str]:
        """A name per value of the policy action (the ``pre`` terms' names, in order)."""
        return [name for term in self.terms("pre").values() for name in term.action_names()]

    def action_from_qpos(self, qpos: Any) -> torch.Tensor:
        """The policy action that commands the (N, n_active) joint position targets ``qpos``
        (the ``pre`` terms' actions side by side; ``qpos`` itself without ``pre`` terms).

        Raises:
            ValueError: a ``pre`` term cannot express joint targets; names the term.
        """
        qpos = torch.as_tensor(qpos, dtype=torch.float32)
        terms = self.terms("pre")
        if not terms:
            return qpos
        parts = []
        for name, term in terms.items():
            try:
                parts.append(torch.as_tensor(term.action_from_qpos(qpos), dtype=torch.float32))
            except NotImplementedError as err:
                raise ValueError(
                    f"actions.{name}: {err}; a scripted demonstration gives joint position targets, so "
                    "every pre action term of the env must implement action_from_qpos"
                ) from None
        return torch.cat(parts, dim=-1)

    def summary_rows(self) -> list[tuple[str, str, str]]:
        return [
            (e.cfg.mode, n, f"{type(e.func).__name__} ({e.func.input_key}, dim {e.func.action_dim})")
            for n, e in self.entries.items()
        ]


def _merge(out: dict, key: str, command: Any) -> None:
    if isinstance(command, dict):
        out.update(command)
    else:
        out[key] = command
