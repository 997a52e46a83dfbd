"""Event manager: startup, reset, interval and custom-mode event functors.

Custom modes are declared in ``env.custom_event_modes`` (or by a functor's
``event_modes`` attribute); a mode that looks like a typo of a known one is a
``ConfigError`` with the suggestion (see :func:`check_event_mode`).

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

import warnings
from typing import Any, Iterable, Optional

import numpy as np
import torch

from embodichain_core.config.checks import check_int, describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import EventCfg
from embodichain_core.managers.manager_base import OWN_SECTION, ValidatedFunctor, BuiltFunctor, ManagerBase
from embodichain_core.sim.backend.env_rows import np_ids
from embodichain_core.utils.suggest import closest, did_you_mean

#: The event modes the env itself runs.
EVENT_MODES = ("startup", "reset", "interval")
#: Largest ``interval_step`` accepted (an interval event fires every that many env steps).
MAX_INTERVAL_STEP = 10_000_000


class EventManager(ManagerBase[EventCfg]):
    """Runs event functors ``f(env, env_ids, **params)`` by mode."""

    section = "events"
    kind = "event"
    cfg_type = EventCfg
    min_argc = 2
    modes = EVENT_MODES

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

    @classmethod
    def validate_section(cls, env_cfg: Any, section: Any = OWN_SECTION, **kwargs: Any) -> dict[str, ValidatedFunctor]:
        """:meth:`ManagerBase.validate_section`, after ``env.custom_event_modes``."""
        check_declared_modes(getattr(env_cfg, "custom_event_modes", None))
        return super().validate_section(env_cfg, section, **kwargs)

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """A known or declared ``mode``; ``interval_step`` and ``is_global``."""
        declared = [*(getattr(env_cfg, "custom_event_modes", None) or []), *getattr(checked.func, "event_modes", ())]
        check_event_mode(checked.cfg.mode, checked.path, declared)
        check_interval(checked.cfg, checked.path, getattr(env_cfg, "max_episode_steps", None), warn)

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
            entry: BuiltFunctor = self.entries[name]
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


def check_event_mode(mode: Any, path: str, declared: Iterable[str] = ()) -> None:
    """Check an event's ``mode`` (``path`` is the entry's path).

    ``startup``/``reset``/``interval`` and declared custom modes (``env.custom_event_modes``
    or a functor's ``event_modes``) are accepted; any other mode is an error, with a
    suggestion when it looks like a typo of a known one (an undeclared mode would never
    fire on its own).
    """
    where = join_path(path, "mode")
    if not isinstance(mode, str) or not mode.strip():
        raise ConfigError(
            where,
            f"expected an event mode ('startup', 'reset', 'interval' or a declared custom mode), got {describe(mode)}",
        )
    known = [*EVENT_MODES, *(str(m) for m in declared)]
    if mode in known:
        return
    if closest(mode.strip(), known):
        raise ConfigError(
            where,
            f"unknown event mode {mode!r}.{did_you_mean(mode.strip(), known)} (a custom mode "
            f"with this name must be declared in env.custom_event_modes)",
        )
    raise ConfigError(
        where,
        f"unknown event mode {mode!r}: not one of {', '.join(repr(m) for m in known)}. A custom mode "
        f"(run by task code with env.event_manager.apply({mode!r}, env_ids)) must be declared in "
        "env.custom_event_modes",
    )


def check_declared_modes(modes: Any, path: str = "env.custom_event_modes") -> list[str]:
    """``custom_event_modes``: a list of non-empty names, none of them a built-in mode."""
    if modes is None:
        return []
    if isinstance(modes, (str, dict)) or not isinstance(modes, (list, tuple)):
        raise ConfigError(path, f"expected a list of mode names, got {describe(modes)}")
    for i, mode in enumerate(modes):
        if not isinstance(mode, str) or not mode.strip():
            raise ConfigError(f"{path}[{i}]", f"expected a mode name, got {describe(mode)}")
        if mode in EVENT_MODES:
            raise ConfigError(f"{path}[{i}]", f"{mode!r} is a built-in event mode; list only custom ones")
    return list(modes)


def check_interval(fcfg: Any, where: str, max_episode_steps: Optional[int], warn: bool = True) -> None:
    """``interval_step``: an int in [1, MAX_INTERVAL_STEP]. A per-env ``interval`` event
    whose step is above ``max_episode_steps`` never fires (its counter restarts with each
    episode): a warning says so (a short smoke-test episode is not an error)."""
    if not isinstance(fcfg.is_global, bool):
        raise ConfigError(join_path(where, "is_global"), f"expected true/false, got {describe(fcfg.is_global)}")
    step = check_int(fcfg.interval_step, join_path(where, "interval_step"), low=1, high=MAX_INTERVAL_STEP)
    limit = max_episode_steps if isinstance(max_episode_steps, int) and max_episode_steps > 0 else None
    if warn and fcfg.mode == "interval" and limit is not None and step > limit and not fcfg.is_global:
        warnings.warn(
            f"{join_path(where, 'interval_step')}: {step} is above max_episode_steps ({limit}): the "
            f"per-env counter restarts with each episode, so this event never fires",
            stacklevel=3,
        )


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
