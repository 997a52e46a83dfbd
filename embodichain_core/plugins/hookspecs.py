"""The hooks (documented in docs/plugins.md), the ``register`` objects they receive and
:data:`KINDS`, the one table of registry kinds."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable

import pluggy

from embodichain_core.plugins.registry import Entry, Registry, check_target_string, is_lazy_target
from embodichain_core.utils.suggest import did_you_mean

PROJECT_NAME = "embodichain"
hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)

FUNCTOR_KINDS = ("event", "observation", "reward", "action", "dataset")
#: Functor category removed by ``filter_visual_rand`` (with names ``randomize_*``).
VISUAL_RANDOMIZATION = "randomization.visual"


class BaseRegister:
    """Registers into ``registry`` on behalf of the plugin ``provider``."""

    def __init__(self, registry: Registry, provider: str):
        self.registry, self.provider = registry, provider

    def _add(self, name: str, target: Any, meta: dict[str, Any] | None = None, *, lazy: bool | None = None) -> Entry:
        return self.registry.add(name, target, self.provider, meta, lazy=lazy)


class FunctorRegister(BaseRegister):
    """``register(name, target, *, kind, category="", description="")``."""

    def __call__(self, name: str, target: Any, *, kind: str, category: str = "", description: str = "") -> Entry:
        if kind not in FUNCTOR_KINDS:
            raise ValueError(
                f"functor {name!r} from {self.provider!r}: unknown kind {kind!r}.{did_you_mean(kind, FUNCTOR_KINDS)}"
            )
        return self._add(name, target, {"kind": kind, "category": category, "description": description})


class RobotRegister(BaseRegister):
    """``register(name, cfg_class)``: lookups ignore case and a trailing ``Cfg``."""

    def __call__(self, name: str, cfg_class: Any) -> Entry:
        return self._add(name, cfg_class)


class SolverRegister(BaseRegister):
    """``register(name, solver_class, description="")``: lookups ignore case and a trailing ``Cfg``."""

    def __call__(self, name: str, solver_class: Any, description: str = "") -> Entry:
        return self._add(name, solver_class, {"description": description})


class SensorRegister(BaseRegister):
    """``register(sensor_type, cfg_class, sensor_class)``; ``entry.resolve_meta("sensor_class")``."""

    def __call__(self, sensor_type: str, cfg_class: Any, sensor_class: Any) -> Entry:
        if is_lazy_target(sensor_class):
            check_target_string(sensor_class, f"sensor {sensor_type!r} from {self.provider!r}")
        return self._add(sensor_type, cfg_class, {"sensor_class": sensor_class})


class AssetRegister(BaseRegister):
    """``register(name, root)``: a data root directory or a zero-argument callable."""

    def __call__(self, name: str, root: Any) -> Entry:
        if not (isinstance(root, (str, os.PathLike)) or callable(root)):
            raise TypeError(
                f"asset root {name!r} from {self.provider!r} must be a path or a callable, got {type(root).__name__}"
            )
        return self._add(name, root, lazy=False)


class TaskRegister(BaseRegister):
    """``register(task_id, entry_point, *, max_episode_steps=None, kwargs=None, config=None, description="")``."""

    def __call__(
        self,
        task_id: str,
        entry_point: str | type,
        *,
        max_episode_steps: int | None = None,
        kwargs: dict[str, Any] | None = None,
        config: Any = None,
        description: str = "",
    ) -> Entry:
        if not (is_lazy_target(entry_point) or isinstance(entry_point, type)):
            raise ValueError(
                f"task {task_id!r} from {self.provider!r}: entry_point must be a 'module:Class' string or the env "
                f"class, got {entry_point!r}"
            )
        limit = None if max_episode_steps is None else int(max_episode_steps)
        meta = {"max_episode_steps": limit, "kwargs": dict(kwargs or {}), "config": config, "description": description}
        return self._add(task_id, entry_point, meta)


class CommandRegister(BaseRegister):
    """``register(name, target, help="")``: ``target(argv: list[str]) -> int``."""

    def __call__(self, name: str, target: Any, help: str = "") -> Entry:  # noqa: A002
        return self._add(name, target, {"help": help})


def class_name_key(name: str) -> str:
    """Case-insensitive key that also accepts a trailing ``Cfg`` (``DexforceW1Cfg``)."""
    key = name.lower()
    return key[:-3] if key.endswith("cfg") and len(key) > 3 else key


@dataclass(frozen=True)
class Kind:
    """One registry kind: its hook, register object, message noun and lookup key."""

    hook: str
    register: type[BaseRegister]
    noun: str
    key: Callable[[str], str] | None = None


#: Every registry kind, in the order the hooks are called.
KINDS: dict[str, Kind] = {
    "commands": Kind("embodichain_register_commands", CommandRegister, "command"),
    "assets": Kind("embodichain_register_assets", AssetRegister, "asset root"),
    "robots": Kind("embodichain_register_robots", RobotRegister, "robot", class_name_key),
    "solvers": Kind("embodichain_register_solvers", SolverRegister, "solver", class_name_key),
    "sensors": Kind("embodichain_register_sensors", SensorRegister, "sensor", class_name_key),
    "functors": Kind("embodichain_register_functors", FunctorRegister, "functor"),
    "tasks": Kind("embodichain_register_tasks", TaskRegister, "task"),
}


def new_registries() -> dict[str, Registry]:
    """A fresh, empty registry of every kind."""
    return {kind: Registry(kind, noun=k.noun, key=k.key) for kind, k in KINDS.items()}


@hookspec
def embodichain_register_functors(register: FunctorRegister) -> None:
    """Register manager functors."""


@hookspec
def embodichain_register_robots(register: RobotRegister) -> None:
    """Register robot config classes by ``class_type``/``robot_type``."""


@hookspec
def embodichain_register_solvers(register: SolverRegister) -> None:
    """Register kinematics solvers by ``solver_cfg.<part>.class_type``."""


@hookspec
def embodichain_register_sensors(register: SensorRegister) -> None:
    """Register sensors by ``sensor_type``."""


@hookspec
def embodichain_register_assets(register: AssetRegister) -> None:
    """Register data roots searched by ``get_data_path``."""


@hookspec
def embodichain_register_tasks(register: TaskRegister) -> None:
    """Register gym tasks (each goes into gymnasium's registry too)."""


@hookspec
def embodichain_register_commands(register: CommandRegister) -> None:
    """Register ``embodichain`` subcommands."""
