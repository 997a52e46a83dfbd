"""The hooks (documented in docs/plugins.md) and the typed ``register`` objects they receive.
Each register class names its registry kind; :data:`KINDS` lists them in hook-call order."""

from __future__ import annotations

import functools
import os
from typing import Any, ClassVar

import pluggy

from embodichain_core.plugins.registry import RegistryEntry, Registry, check_target_string, is_lazy_target
from embodichain_core.utils.suggest import did_you_mean

PROJECT_NAME = "embodichain"
hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)

FUNCTOR_KINDS = ("event", "observation", "reward", "action", "dataset")
#: The viewers ``sim_cfg.viewer`` can open (MuJoCo's native window, a page in the browser).
VIEWER_NAMES = ("native", "browser")
#: Functor category removed by ``filter_visual_rand`` (with names ``randomize_*``).
VISUAL_RANDOMIZATION = "randomization.visual"


def visual_randomization(name: str, category: str) -> bool:
    """What ``filter_visual_rand`` removes: a functor named ``randomize_*`` of category
    :data:`VISUAL_RANDOMIZATION`."""
    return name.startswith("randomize_") and category == VISUAL_RANDOMIZATION


def class_name_key(name: str) -> str:
    """Case-insensitive key that also accepts a trailing ``Cfg`` (``DexforceW1Cfg``)."""
    key = name.lower()
    return key[:-3] if key.endswith("cfg") and len(key) > 3 else key


#: kind -> register class, in the order the hooks are called (the order the classes are defined).
KINDS: dict[str, type[BaseRegister]] = {}


class BaseRegister:
    """Registers into ``registry`` for the plugin ``provider``. A subclass names its registry
    ``kind`` (hook ``embodichain_register_<kind>``) and the ``noun`` of its messages; with
    ``class_names``, lookups ignore case and a trailing ``Cfg`` (:func:`class_name_key`)."""

    kind: ClassVar[str]
    noun: ClassVar[str]
    class_names: ClassVar[bool] = False

    def __init_subclass__(cls) -> None:
        KINDS[cls.kind] = cls

    def __init__(self, registry: Registry, provider: str):
        self.registry, self.provider = registry, provider

    def _add(
        self, name: str, target: Any, meta: dict[str, Any] | None = None, *, lazy: bool | None = None
    ) -> RegistryEntry:
        return self.registry.add(name, target, self.provider, meta, lazy=lazy)

    def _check(self, ok: bool, name: str, problem: str, error: type[Exception] = ValueError) -> None:
        if not ok:
            raise error(f"{self.noun} {name!r} from {self.provider!r}: {problem}")


class CommandRegister(BaseRegister):
    """``register(name, target, help="")``: ``target(argv: list[str]) -> int``."""

    kind, noun = "commands", "command"

    def __call__(self, name: str, target: Any, help: str = "") -> RegistryEntry:  # noqa: A002
        return self._add(name, target, {"help": help})


class AssetRegister(BaseRegister):
    """``register(name, root)``: a data directory, or a zero-argument callable returning one
    (called once, on first use)."""

    kind, noun = "assets", "asset root"

    def __call__(self, name: str, root: Any) -> RegistryEntry:
        ok = isinstance(root, (str, os.PathLike)) or callable(root)
        self._check(ok, name, f"must be a path or a callable, got {type(root).__name__}", TypeError)
        return self._add(name, functools.cache(root) if callable(root) else root, lazy=False)


class RobotRegister(BaseRegister):
    """``register(name, cfg_class)``: lookups ignore case and a trailing ``Cfg``."""

    kind, noun, class_names = "robots", "robot", True

    def __call__(self, name: str, cfg_class: Any) -> RegistryEntry:
        return self._add(name, cfg_class)


class SolverRegister(BaseRegister):
    """``register(name, solver_class, description="")``: lookups ignore case and a trailing ``Cfg``."""

    kind, noun, class_names = "solvers", "solver", True

    def __call__(self, name: str, solver_class: Any, description: str = "") -> RegistryEntry:
        return self._add(name, solver_class, {"description": description})


class SensorRegister(BaseRegister):
    """``register(sensor_type, cfg_class, sensor_class)``; ``entry.resolve_meta("sensor_class")``."""

    kind, noun, class_names = "sensors", "sensor", True

    def __call__(self, sensor_type: str, cfg_class: Any, sensor_class: Any) -> RegistryEntry:
        if is_lazy_target(sensor_class):
            check_target_string(sensor_class, f"sensor {sensor_type!r} from {self.provider!r}")
        return self._add(sensor_type, cfg_class, {"sensor_class": sensor_class})


class FunctorRegister(BaseRegister):
    """``register(name, target, *, kind, category="", description="")``."""

    kind, noun = "functors", "functor"

    def __call__(
        self, name: str, target: Any, *, kind: str, category: str = "", description: str = ""
    ) -> RegistryEntry:
        self._check(kind in FUNCTOR_KINDS, name, f"unknown kind {kind!r}.{did_you_mean(kind, FUNCTOR_KINDS)}")
        return self._add(name, target, {"kind": kind, "category": category, "description": description})


class TaskRegister(BaseRegister):
    """``register(task_id, entry_point, *, max_episode_steps=None, kwargs=None, config=None, description="")``."""

    kind, noun = "tasks", "task"

    def __call__(
        self,
        task_id: str,
        entry_point: str | type,
        *,
        max_episode_steps: int | None = None,
        kwargs: dict[str, Any] | None = None,
        config: Any = None,
        description: str = "",
    ) -> RegistryEntry:
        ok = is_lazy_target(entry_point) or isinstance(entry_point, type)
        self._check(ok, task_id, f"entry_point must be a 'module:Class' string or the env class, got {entry_point!r}")
        limit = None if max_episode_steps is None else int(max_episode_steps)
        meta = {"max_episode_steps": limit, "kwargs": dict(kwargs or {}), "config": config, "description": description}
        return self._add(task_id, entry_point, meta)


class ViewerRegister(BaseRegister):
    """``register(name, opener, description="")``: ``name`` is one of :data:`VIEWER_NAMES`;
    ``opener(env, name, port=...)`` opens it on a built env and returns its session
    (``before_step()``, ``after_step(obs, reward, info)``, ``close()``). A ``"module:function"``
    opener keeps a headless run from importing it."""

    kind, noun = "viewers", "viewer"

    def __call__(self, name: str, opener: Any, description: str = "") -> RegistryEntry:
        hint = did_you_mean(str(name), VIEWER_NAMES)
        self._check(name in VIEWER_NAMES, name, f"a viewer is registered as one of {', '.join(VIEWER_NAMES)}.{hint}")
        ok, got = is_lazy_target(opener) or callable(opener), type(opener).__name__
        self._check(ok, name, f"the opener must be a 'module:function' string or a callable, got {got}", TypeError)
        return self._add(name, opener, {"description": description})


def hook_name(kind: str) -> str:
    """The hook filling the registry of ``kind`` (``"embodichain_register_functors"``)."""
    return f"embodichain_register_{kind}"


def new_registries() -> dict[str, Registry]:
    """A fresh, empty registry of every kind."""
    return {k: Registry(k, noun=r.noun, key=class_name_key if r.class_names else None) for k, r in KINDS.items()}


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


@hookspec
def embodichain_register_viewers(register: ViewerRegister) -> None:
    """Register the viewers a non-headless env opens (``sim_cfg.viewer``)."""
