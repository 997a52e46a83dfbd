"""Event manager: startup, reset, interval and custom-mode event functors.

Custom modes are declared in ``env.custom_event_modes`` (or by a functor's
``event_modes`` attribute); a mode that looks like a typo of a known one is a
``ConfigError`` with the suggestion (see :func:`~embodichain_core.config.sections.check_event_mode`).

Interval counters are per env and restart with each env's episode, so an
``interval_step=5`` event fires on steps 5, 10, ... of every episode of every env
(``is_global=True`` keeps one counter and fires for all envs at once).

The per-env counters are kept as phases: an env's counter is the number of interval
ticks since its last reset, so it fires on the ticks congruent to its reset tick
modulo ``interval_step``. The envs due on a tick are cached per residue and change
only when an env resets, so a step costs a dictionary lookup instead of a pass over
every env's counter (``env_throughput`` at 64 envs fires on every step for a few envs).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from embodichain_core.config.sections import check_event_mode, check_interval
from embodichain_core.managers.cfg import EventCfg
from embodichain_core.managers.manager_base import FunctorEntry, ManagerBase
from embodichain_core.managers.param_rules import check_param_types
from embodichain_core.sim.backend.env_rows import np_ids


class EventManager(ManagerBase[EventCfg]):
    """Runs event functors ``f(env, env_ids, **params)`` by mode."""

    section = "events"
    kind = "event"
    cfg_type = EventCfg
    min_argc = 2

    def __init__(self, cfg: Any, env: Any, path: str | None = None):
        super().__init__(cfg, env, path)
        self._modes: dict[str, list[str]] = {}
        self._tick = 0  # interval ticks (steps) since construction
        self._global_start: dict[str, int] = {}  # global events: the tick their counter restarted at
        self._phases: dict[str, _Phases] = {}  # per-env events
        for name, entry in self.entries.items():
            self._modes.setdefault(entry.cfg.mode, []).append(name)
            if entry.cfg.mode == "interval":
                if entry.cfg.is_global:
                    self._global_start[name] = 0
                else:
                    self._phases[name] = _Phases(env.num_envs, int(entry.cfg.interval_step))

    def _check(self, func: Any, cfg: EventCfg, where: str) -> None:
        super()._check(func, cfg, where)
        env_cfg = getattr(self._env, "cfg", None)
        declared = [*(getattr(env_cfg, "custom_event_modes", None) or []), *getattr(func, "event_modes", ())]
        check_event_mode(cfg.mode, where, declared)
        check_interval(cfg, where, getattr(env_cfg, "max_episode_steps", None))
        check_param_types(func, cfg.params, where, self.min_argc)

    @property
    def available_modes(self) -> list[str]:
        return list(self._modes)

    def functors_of(self, mode: str) -> list[str]:
        return list(self._modes.get(mode, []))

    def apply(self, mode: str, env_ids: Any = None) -> None:
        """Run the functors of ``mode``. ``interval`` advances the counters one step."""
        if mode == "interval":
            if env_ids is not None:
                raise ValueError("interval events run for all envs; do not pass env_ids")
            if self._global_start or self._phases:  # called every step: nothing to do without interval events
                self._apply_interval()
            return
        for name in self._modes.get(mode, []):
            ids = env_ids
            if ids is None and mode != "startup":
                ids = torch.arange(self._env.num_envs)
            self.entries[name](self._env, ids)

    def _apply_interval(self) -> None:
        self._tick += 1
        tick = self._tick
        for name in self._modes["interval"]:
            entry: FunctorEntry = self.entries[name]
            phases = self._phases.get(name)
            if phases is None:  # global
                if (tick - self._global_start[name]) % entry.cfg.interval_step == 0:
                    entry(self._env, None)
                continue
            due = phases.due(tick)
            if len(due):
                entry(self._env, torch.from_numpy(due.copy()))  # a copy: the cache outlives the call

    def interval_counters(self, name: str) -> np.ndarray:
        """The steps counted since each env's (or, for a global event, the last full)
        reset by interval event ``name``: ``(num_envs,)``, or ``(1,)`` for a global one."""
        if name in self._global_start:
            return np.array([self._tick - self._global_start[name]], dtype=np.int64)
        if name not in self._phases:
            raise KeyError(f"{name!r} is not an interval event; interval events: {self.functors_of('interval')}")
        return self._phases[name].counters(self._tick)

    def reset(self, env_ids: Any = None) -> dict:
        """Restart the per-env interval counters and reset class functors."""
        if self._global_start or self._phases:
            rows = None if env_ids is None else np_ids(env_ids, self._env.num_envs)
            for name in self._global_start:
                if rows is None or len(rows) == self._env.num_envs:
                    self._global_start[name] = self._tick
            for phases in self._phases.values():
                phases.restart(rows, self._tick)
        return super().reset(env_ids)

    def summary_rows(self) -> list[tuple[str, str, str]]:
        rows = []
        for mode, names in self._modes.items():
            for n in names:
                cfg = self.entries[n].cfg
                detail = getattr(cfg.func, "__name__", str(cfg.func))
                if mode == "interval":
                    detail += f" (every {cfg.interval_step} steps{', global' if cfg.is_global else ''})"
                rows.append((mode, n, detail))
        return rows


class _Phases:
    """Per-env interval counters of one event, as each env's reset tick modulo the interval.

    An env fires on tick ``t`` when ``t - reset_tick`` is a multiple of ``interval``,
    so the envs due on ``t`` are those whose phase is ``t % interval``; they are
    computed once per residue and kept until an env of that residue resets.
    """

    def __init__(self, num_envs: int, interval: int):
        self.interval = interval
        self.start = np.zeros(num_envs, dtype=np.int64)  # the tick of each env's last reset
        self._due: dict[int, np.ndarray] = {}  # residue -> the envs whose start has it

    def due(self, tick: int) -> np.ndarray:
        """The envs whose counter reaches a multiple of the interval on ``tick`` (sorted)."""
        residue = tick % self.interval
        due = self._due.get(residue)
        if due is None:
            due = self._due[residue] = np.flatnonzero(self.start % self.interval == residue)
        return due

    def restart(self, rows: np.ndarray | None, tick: int) -> None:
        """The counters of ``rows`` (None: every env) start again from ``tick``."""
        if rows is None:
            self.start[:] = tick
            self._due.clear()
            return
        self._due.pop(tick % self.interval, None)
        for old in self.start[rows].tolist():  # few rows at a time: cheaper than a set of them
            self._due.pop(old % self.interval, None)
        self.start[rows] = tick

    def counters(self, tick: int) -> np.ndarray:
        return tick - self.start
