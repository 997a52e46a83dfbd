"""The embodichain plugin host (docs/plugins.md): :data:`hookimpl` and the typed register
objects for plugin authors, and the registry accessors (loading the plugins on first use),
which take a bare or a qualified (``<plugin>/<name>``) name. The names imported here with
``as`` are its public API."""

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import Any

from embodichain_core.plugins.hookspecs import FunctorRegister as FunctorRegister
from embodichain_core.plugins.hookspecs import RobotRegister as RobotRegister
from embodichain_core.plugins.hookspecs import SensorRegister as SensorRegister
from embodichain_core.plugins.hookspecs import TaskRegister as TaskRegister
from embodichain_core.plugins.hookspecs import ViewerRegister as ViewerRegister
from embodichain_core.plugins.hookspecs import hookimpl as hookimpl
from embodichain_core.plugins.hookspecs import visual_randomization
from embodichain_core.plugins.manager import CORE_PLUGIN_NAME as CORE_PLUGIN_NAME
from embodichain_core.plugins.manager import NameClash as NameClash
from embodichain_core.plugins.manager import NameClashWarning as NameClashWarning
from embodichain_core.plugins.manager import PluginLoadWarning as PluginLoadWarning
from embodichain_core.plugins.manager import failed_plugins as failed_plugins
from embodichain_core.plugins.manager import get_plugin_manager as get_plugin_manager
from embodichain_core.plugins.manager import get_registry as get_registry
from embodichain_core.plugins.manager import isolated_plugins as isolated_plugins
from embodichain_core.plugins.manager import list_plugins as list_plugins
from embodichain_core.plugins.manager import load_plugins as load_plugins
from embodichain_core.plugins.manager import register_plugin as register_plugin
from embodichain_core.plugins.manager import unregister_plugin as unregister_plugin
from embodichain_core.plugins.registry import AmbiguousNameError as AmbiguousNameError
from embodichain_core.plugins.registry import RegistryEntry

# The registry of each kind; RegistryEntry.meta holds a functor's kind/category/description, a
# sensor's sensor_class, a task's max_episode_steps/kwargs/config/description, a command's help.
functor_registry = partial(get_registry, "functors")
robot_registry = partial(get_registry, "robots")
solver_registry = partial(get_registry, "solvers")
sensor_registry = partial(get_registry, "sensors")
asset_registry = partial(get_registry, "assets")
task_registry = partial(get_registry, "tasks")
command_registry = partial(get_registry, "commands")
viewer_registry = partial(get_registry, "viewers")


def get_functor(name: str) -> Any:
    """The functor registered as ``name`` (imported on first use)."""
    return functor_registry().get(name)


def get_robot_cfg_class(name: str) -> Any:
    """The robot config class for a ``class_type``/``robot_type`` (``"DexforceW1"``)."""
    return robot_registry().get(name)


def get_solver_class(name: str) -> Any:
    """The solver class for a ``solver_cfg.<part>.class_type``."""
    return solver_registry().get(name)


def get_sensor_classes(sensor_type: str) -> tuple[Any, Any]:
    """``(cfg_class, sensor_class)`` registered for ``sensor_type``."""
    entry = sensor_registry().entry(sensor_type)
    return entry.resolve(), entry.resolve_meta("sensor_class")


def get_asset_root(name: str | RegistryEntry) -> Path:
    """The data root registered as ``name`` (or by an ``assets`` entry); a callable root is called once."""
    entry = name if isinstance(name, RegistryEntry) else asset_registry().entry(name)
    root = entry.resolve()
    root = root() if callable(root) else root
    if not root:
        raise TypeError(f"asset root {entry.name!r} from {entry.provider!r} is {root!r}, not a directory")
    return Path(root)


def is_visual_randomization(name: str) -> bool:
    """True for a registered functor that ``filter_visual_rand`` removes (an ambiguous name is
    not one: it fails when resolved)."""
    try:
        entry = functor_registry().find(name)
    except AmbiguousNameError:
        return False
    return entry is not None and visual_randomization(entry.name, entry.meta["category"])


def name_clashes(provider: str | None = None) -> list[NameClash]:
    """Bare names several installed plugins register (only ``provider``'s when given)."""
    return load_plugins().name_clashes(provider)
