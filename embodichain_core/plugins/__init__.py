"""The embodichain plugin host (docs/plugins.md): :data:`hookimpl` for plugin authors, and
registry accessors (loading the plugins on first use) taking a bare or qualified name."""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import Any

from embodichain_core.plugins import manager
from embodichain_core.plugins.hookspecs import (
    VISUAL_RANDOMIZATION,
    FunctorRegister,
    RobotRegister,
    SensorRegister,
    TaskRegister,
    hookimpl,
)
from embodichain_core.plugins.manager import (
    CORE_PLUGIN_NAME,
    NameClashWarning,
    PluginLoadWarning,
    failed_plugins,
    get_plugin_manager,
    get_registry,
    isolated_plugins,
    list_plugins,
    load_plugins,
    register_plugin,
    unregister_plugin,
)
from embodichain_core.plugins.registry import AmbiguousNameError, NameClash, describe_target

__all__ = [
    "hookimpl",
    "FunctorRegister",
    "RobotRegister",
    "SensorRegister",
    "TaskRegister",
    "AmbiguousNameError",
    "NameClashWarning",
    "PluginLoadWarning",
    "CORE_PLUGIN_NAME",
    "manager",
    "get_plugin_manager",
    "load_plugins",
    "register_plugin",
    "unregister_plugin",
    "isolated_plugins",
    "list_plugins",
    "failed_plugins",
    "name_clashes",
    "get_registry",
    "functor_registry",
    "robot_registry",
    "solver_registry",
    "sensor_registry",
    "asset_registry",
    "task_registry",
    "command_registry",
    "get_functor",
    "get_robot_cfg_class",
    "get_solver_class",
    "get_sensor_classes",
    "get_asset_root",
    "asset_roots",
    "is_visual_randomization",
    "task_episode_limit",
]


# Each accessor returns the registry of one kind (loading the plugins first). Entry meta:
# functors ``kind``/``category``/``description``; sensors ``sensor_class``; tasks
# ``max_episode_steps``/``kwargs``/``config``/``description``; commands ``help``. Robot,
# solver and sensor lookups ignore case and a trailing ``Cfg``.
functor_registry = partial(get_registry, "functors")
robot_registry = partial(get_registry, "robots")
solver_registry = partial(get_registry, "solvers")
sensor_registry = partial(get_registry, "sensors")
asset_registry = partial(get_registry, "assets")
task_registry = partial(get_registry, "tasks")
command_registry = partial(get_registry, "commands")


def get_functor(name: str) -> Any:
    """The functor registered as ``name`` (imported on first use)."""
    return functor_registry().get(name)


def get_robot_cfg_class(name: str) -> Any:
    """The robot config class for a ``class_type``/``robot_type`` (``"DexforceW1"``)."""
    return robot_registry().get(name)


def get_solver_class(name: str) -> Any:
    """The solver class registered as ``name`` (a ``solver_cfg.<part>.class_type``)."""
    return solver_registry().get(name)


def get_sensor_classes(sensor_type: str) -> tuple[Any, Any]:
    """``(cfg_class, sensor_class)`` registered for ``sensor_type``."""
    entry = sensor_registry().entry(sensor_type)
    return entry.resolve(), entry.resolve_meta("sensor_class")


def get_asset_root(name: str) -> Path:
    """The data root registered as ``name`` (a callable root is called once)."""
    entry = asset_registry().entry(name)
    if "root_path" not in entry.meta:
        root = entry.resolve()
        entry.meta["root_path"] = Path(root() if callable(root) else root)
    return entry.meta["root_path"]


def asset_roots() -> dict[str, Path]:
    """Every registered data root by name (a clashing name once per plugin, qualified)."""
    registry = asset_registry()
    clashing = registry.clashes()
    names = [registry.qualified_name(e) if e.name in clashing else e.name for e in registry.entries()]
    return {name: get_asset_root(name) for name in names}


def is_visual_randomization(name: str) -> bool:
    """True for a ``randomize_*`` functor of category ``"randomization.visual"`` (an ambiguous
    name is not; it fails when resolved)."""
    try:
        entry = functor_registry().find(name)
    except AmbiguousNameError:
        return False
    return (
        entry is not None and entry.name.startswith("randomize_") and entry.meta.get("category") == VISUAL_RANDOMIZATION
    )


def name_clashes(provider: str | None = None) -> list[NameClash]:
    """Bare names several installed plugins register (only ``provider``'s when given)."""
    return load_plugins().name_clashes(provider)


def task_episode_limit(env_cls: type) -> int | None:
    """The ``max_episode_steps`` the tasks of ``env_cls`` register (``None``: none, or they differ)."""
    target = describe_target(env_cls)
    limits = {e.meta.get("max_episode_steps") for e in task_registry().ordered_entries() if e.target_repr == target}
    limits.discard(None)
    return limits.pop() if len(limits) == 1 else None
