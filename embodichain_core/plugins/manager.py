"""The plugin host: builds the pluggy manager, loads plugins, fills the registries.

``load_plugins()`` is lazy and idempotent. It registers the core's own defaults
(:mod:`embodichain_core.plugins.builtin`), loads the setuptools entry points of the
group ``"embodichain"`` sorted by plugin name (so the outcome never depends on the
install or discovery order), checks every plugin for misspelled hooks, and calls each
plugin's register hooks. A plugin is named after its distribution (see
:mod:`embodichain_core.plugins.clashes`). A plugin that fails (import error, unknown
hook, bad hook signature, a hook raising, registering one name twice with different
targets) is reported by name and error in one line as a :class:`PluginLoadWarning` (the
traceback is kept for ``failed_plugins()`` and ``embodichain list plugins -v``),
contributes nothing (its registrations are rolled back) and does not take the others
down. A name another plugin registered too is *not* a failure: both entries stay,
under their qualified names ``<plugin>:<name>`` (see :mod:`embodichain_core.plugins.names`).

Environment variables:
    ``EMBODICHAIN_BLOCK_PLUGINS``: comma-separated plugin (distribution) or entry point
        names to skip (``*`` skips all entry points).
    ``EMBODICHAIN_PLUGIN_PRIORITY``: comma-separated plugin names; the first listed
        provider of an ambiguous bare name wins.
    ``EMBODICHAIN_TRACE_PLUGINS=1``: trace hook calls to stderr.
"""

from __future__ import annotations

import functools
import inspect
import os
import sys
import threading
import traceback
import types
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Iterable, Iterator

import pluggy

from embodichain_core.plugins import hookspecs
from embodichain_core.plugins.clashes import NameClash, entry_point_clashes, name_clashes, name_entry_points
from embodichain_core.plugins.hookspecs import PROJECT_NAME, REGISTER_CLASSES, REGISTER_HOOKS
from embodichain_core.plugins.names import NameClashWarning, join_names
from embodichain_core.plugins.registry import KINDS, Entry, Registry, new_registries
from embodichain_core.utils.suggest import did_you_mean

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

ENTRY_POINT_GROUP = "embodichain"
BLOCK_ENV = "EMBODICHAIN_BLOCK_PLUGINS"
TRACE_ENV = "EMBODICHAIN_TRACE_PLUGINS"
#: Provider name of the core's own registrations.
CORE_PLUGIN_NAME = "embodichain-core"


class PluginLoadWarning(UserWarning):
    """A plugin failed to load and was skipped."""


@dataclass
class PluginInfo:
    """What ``list_plugins()`` reports about one plugin.

    Attributes:
        name: plugin name: the distribution name (PEP 503-normalized) for an entry
            point, the given name for a runtime plugin. Qualified names use it.
        version: the distribution's version, ``""`` when unknown.
        status: ``"loaded"``, ``"failed"`` or ``"blocked"``.
        module: the entry point value or the plugin object's module.
        error: the failure's traceback (``""`` unless failed).
        registered: names registered per kind (``{"functors": [...], ...}``).
        entry_point: the entry point's name (``""`` for runtime plugins).
    """

    name: str
    version: str = ""
    status: str = "loaded"
    module: str = ""
    error: str = ""
    registered: dict[str, list[str]] = field(default_factory=dict)
    entry_point: str = ""

    @property
    def error_summary(self) -> str:
        """The last non-empty line of the traceback (``"ImportError: ..."``)."""
        lines = [line for line in self.error.strip().splitlines() if line.strip()]
        return lines[-1].strip() if lines else ""


class EmbodichainPluginManager(pluggy.PluginManager):
    """pluggy manager owning the registries filled by its plugins.

    Functions named ``embodichain_register_*`` are hook implementations even
    without ``@hookimpl``, so a misspelled hook name is caught as an unknown hook.
    """

    def __init__(self) -> None:
        super().__init__(PROJECT_NAME)
        self.add_hookspecs(hookspecs)
        self.registries: dict[str, Registry] = new_registries()
        self.infos: dict[str, PluginInfo] = {}
        #: entry point names declared by several distributions -> their plugin names.
        self.entry_point_clashes: dict[str, list[str]] = {}
        self.loaded = False
        self.lock = threading.RLock()
        if os.environ.get(TRACE_ENV, "").strip() not in ("", "0"):
            self.trace.root.setwriter(sys.stderr.write)
            self.enable_tracing()

    def parse_hookimpl_opts(self, plugin: Any, name: str) -> Any:
        opts = super().parse_hookimpl_opts(plugin, name)
        if opts is None and name.startswith("embodichain_register") and _is_function(plugin, name):
            return {}
        return opts

    def registry(self, kind: str) -> Registry:
        """The registry of ``kind`` (``"functors"``, ``"robots"``, ...)."""
        try:
            return self.registries[kind]
        except KeyError:
            raise ValueError(f"unknown registry kind {kind!r}.{did_you_mean(kind, KINDS)}") from None

    def failed(self) -> list[tuple[str, str]]:
        """``(name, traceback)`` of every plugin that failed to load."""
        return [(i.name, i.error) for i in self.infos.values() if i.status == "failed"]

    def name_clashes(self, provider: str | None = None) -> list[NameClash]:
        """Bare names registered by several plugins (only ``provider``'s when given)."""
        return name_clashes(self.registries, provider)


def _is_function(plugin: Any, name: str) -> bool:
    static = inspect.getattr_static(plugin, name, None)
    return inspect.isfunction(static) or isinstance(static, (staticmethod, classmethod, types.MethodType))


_PM: EmbodichainPluginManager | None = None
_GLOBAL_LOCK = threading.Lock()


def get_plugin_manager() -> EmbodichainPluginManager:
    """The current plugin manager (created on first call; plugins not loaded yet)."""
    global _PM
    with _GLOBAL_LOCK:
        if _PM is None:
            _PM = EmbodichainPluginManager()
        return _PM


def load_plugins(*, entry_points: bool = True, exclude: frozenset[str] = frozenset()) -> EmbodichainPluginManager:
    """Load the built-ins and the installed plugins once; later calls are no-ops.

    Args:
        entry_points: also load the ``"embodichain"`` entry points (the default).
        exclude: plugin names not to load (``isolated_plugins`` uses it).

    Returns:
        The plugin manager, with its registries filled.
    """
    pm = get_plugin_manager()
    with pm.lock:
        if pm.loaded:
            return pm
        pm.loaded = True
        from embodichain_core import __version__
        from embodichain_core.plugins import builtin

        pm.register(builtin, name=CORE_PLUGIN_NAME)
        pm.infos[CORE_PLUGIN_NAME] = PluginInfo(CORE_PLUGIN_NAME, __version__, module=builtin.__name__)
        if entry_points:
            _load_entry_points(pm, exclude)
        for info in list(pm.infos.values()):
            if info.status == "loaded":
                _activate(pm, info)
        pm.check_pending()
    return pm


def _iter_entry_points() -> list[EntryPoint]:
    """Every ``"embodichain"`` entry point, duplicates of a name included (test seam)."""
    import importlib.metadata

    return list(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP))


def blocked_plugins() -> set[str]:
    """Plugin or entry point names listed in ``EMBODICHAIN_BLOCK_PLUGINS``."""
    return {n.strip() for n in os.environ.get(BLOCK_ENV, "").split(",") if n.strip()}


def _load_entry_points(pm: EmbodichainPluginManager, exclude: frozenset[str] = frozenset()) -> None:
    blocked = blocked_plugins()
    named = [(n, ep) for n, ep in name_entry_points(_iter_entry_points()) if n not in exclude]
    _report_entry_point_clashes(pm, entry_point_clashes(named))
    for name, ep in named:
        if name in pm.infos:
            continue
        dist = getattr(ep, "dist", None)
        info = pm.infos[name] = PluginInfo(
            name, getattr(dist, "version", "") or "", module=ep.value, entry_point=ep.name
        )
        if blocked & {name, ep.name, "*"}:
            info.status = "blocked"
            pm.set_blocked(name)
            continue
        try:
            plugin = ep.load()
            if plugin is None:
                raise TypeError(f"entry point {ep.name!r} = {ep.value!r} loaded None")
            pm.register(plugin, name=name)
        except Exception:
            _fail(pm, info)


def _report_entry_point_clashes(pm: EmbodichainPluginManager, clashes: dict[str, list[str]]) -> None:
    """Warn about entry point names several distributions declare (all of them still load)."""
    pm.entry_point_clashes = clashes
    for ep_name, plugins in clashes.items():
        warnings.warn(
            f"the embodichain entry point {ep_name!r} is declared by {len(plugins)} distributions: "
            f"{join_names([repr(p) for p in plugins])}. All of them are loaded, each under its "
            f"distribution name; name the entry point after its distribution to silence this.",
            NameClashWarning,
            stacklevel=4,
        )


def _activate(pm: EmbodichainPluginManager, info: PluginInfo) -> None:
    """Validate one registered plugin and run its hooks; report a failure."""
    try:
        _check_hooks(pm, info.name)
        info.registered = _run_register_hooks(pm, info.name)
    except Exception:
        _fail(pm, info)


def _fail(pm: EmbodichainPluginManager, info: PluginInfo) -> None:
    info.status, info.error, info.registered = "failed", traceback.format_exc(), {}
    if pm.get_plugin(info.name) is not None:
        pm.unregister(name=info.name)
    exc = sys.exc_info()[1]
    lines = str(exc).strip().splitlines()
    summary = f"{type(exc).__name__}: {lines[0] if lines else ''}" if exc is not None else info.error_summary
    # One line: the warning shows on every command; the traceback is one request away.
    warnings.warn(
        f"embodichain plugin {info.name!r} failed to load and was skipped: {summary} "
        "(the traceback: `embodichain list plugins -v`, or embodichain_core.plugins.failed_plugins())",
        PluginLoadWarning,
        stacklevel=3,
    )


def _check_hooks(pm: EmbodichainPluginManager, name: str) -> None:
    """Raise ``PluginValidationError`` when plugin ``name`` implements an unknown hook."""
    plugin = pm.get_plugin(name)
    for caller in pm.get_hookcallers(plugin) or []:
        if caller.has_spec():
            continue
        known = [h for h in vars(pm.hook) if not h.startswith("_") and getattr(pm.hook, h).has_spec()]
        raise pluggy.PluginValidationError(
            plugin, f"plugin {name!r} implements unknown hook {caller.name!r}.{did_you_mean(caller.name, known)}"
        )


def _run_register_hooks(pm: EmbodichainPluginManager, name: str) -> dict[str, list[str]]:
    """Call plugin ``name``'s register hooks; all-or-nothing (only its own entries are
    rolled back when it raises). Returns names per kind."""
    plugin = pm.get_plugin(name)
    added: list[tuple[Registry, Entry]] = []
    try:
        for kind in KINDS:
            hook_name = REGISTER_HOOKS[kind]
            if not any(impl.plugin is plugin for impl in getattr(pm.hook, hook_name).get_hookimpls()):
                continue
            registry = pm.registries[kind]
            register = REGISTER_CLASSES[kind](registry, name, functools.partial(_record, added, registry))
            others = [p for p in pm.get_plugins() if p is not plugin]
            pm.subset_hook_caller(hook_name, others)(register=register)
    except BaseException:
        for registry, entry in reversed(added):
            registry.remove(entry.name, provider=entry.provider)
        raise
    registered: dict[str, list[str]] = {}
    for registry, entry in added:
        registered.setdefault(registry.kind, []).append(entry.name)
    return registered


def _record(added: list[tuple[Registry, Entry]], registry: Registry, entry: Entry) -> None:
    added.append((registry, entry))


def register_plugin(obj: Any, name: str | None = None) -> str:
    """Register a plugin object or module at runtime and run its register hooks.

    Unlike entry points, a failure raises (and leaves nothing registered).

    Args:
        obj: a module, class or instance with ``@hookimpl`` functions.
        name: plugin/provider name; defaults to the module or class name.

    Returns:
        The plugin name.
    """
    pm = load_plugins()
    with pm.lock:
        name = name or _default_name(obj)
        if pm.register(obj, name=name) is None:
            raise ValueError(f"plugin {name!r} is blocked")
        module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "")
        info = PluginInfo(name, module=str(module))
        try:
            _check_hooks(pm, name)
            info.registered = _run_register_hooks(pm, name)
        except BaseException:
            pm.unregister(name=name)
            raise
        pm.infos[name] = info
    return name


def unregister_plugin(name: str) -> None:
    """Remove plugin ``name`` and everything it registered."""
    pm = load_plugins()
    with pm.lock:
        for registry in pm.registries.values():
            for entry in registry.by_provider(name):
                registry.remove(entry.name, provider=name)
        if pm.get_plugin(name) is not None:
            pm.unregister(name=name)
        pm.infos.pop(name, None)


def _default_name(obj: Any) -> str:
    if isinstance(obj, types.ModuleType):
        return obj.__name__
    cls = obj if inspect.isclass(obj) else type(obj)
    return f"{cls.__module__}.{cls.__qualname__}"


@contextmanager
def isolated_plugins(
    *, load_entry_points: bool = False, exclude: Iterable[str] = ()
) -> Iterator[EmbodichainPluginManager]:
    """Swap in a fresh manager and empty registries; restore everything on exit.

    Only the built-ins are loaded (entry points too when ``load_entry_points``, except
    the plugins named in ``exclude``). gymnasium ids the block's plugins registered are
    removed on exit; an id of the outer manager they replaced meanwhile is restored.

    Example:
        >>> with isolated_plugins() as pm:  # doctest: +SKIP
        ...     register_plugin(MyPlugin())
        ...     assert "my_functor" in pm.registry("functors")
    """
    global _PM
    with _GLOBAL_LOCK:
        saved, _PM = _PM, EmbodichainPluginManager()
    try:
        yield load_plugins(entry_points=load_entry_points, exclude=frozenset(exclude))
    finally:
        with _GLOBAL_LOCK:
            pm, _PM = _PM, saved
        if pm is not None:
            pm.registries["tasks"].release_gym()  # type: ignore[attr-defined]


def list_plugins() -> list[PluginInfo]:
    """Every known plugin (loaded, failed or blocked), in load order."""
    return list(load_plugins().infos.values())


def failed_plugins() -> list[tuple[str, str]]:
    """``(name, traceback)`` of the plugins that failed to load."""
    return load_plugins().failed()


def known_providers() -> set[str]:
    """Names of every known plugin (loaded, failed or blocked): the prefixes of qualified names."""
    return set(load_plugins().infos)


def get_registry(kind: str) -> Registry:
    """The registry of ``kind`` (loads plugins first).

    Kinds: ``functors``, ``robots``, ``solvers``, ``sensors``, ``assets``, ``tasks``, ``commands``.
    """
    return load_plugins().registry(kind)


def is_qualified_name(name: Any) -> bool:
    """True for ``"<plugin>:<name>"`` whose prefix is a known plugin's name.

    This is how a qualified name is told from a ``"module:attr"`` import path (which
    also has a colon): a prefix naming a known plugin wins; anything else is a path.
    """
    if not isinstance(name, str) or ":" not in name:
        return False
    return name.partition(":")[0] in known_providers()
