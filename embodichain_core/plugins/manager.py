"""The plugin host: loads the core's and the installed plugins (entry point group
``"embodichain"``, sorted by plugin name), fills the registries, mirrors the tasks into
gymnasium. Each plugin's hooks write into staging registries merged on success: a plugin
that fails contributes nothing and is reported in one line (:class:`PluginLoadWarning`).
"""

from __future__ import annotations

import functools
import inspect
import os
import re
import sys
import threading
import traceback
import types
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator

import pluggy

from embodichain_core.plugins import hookspecs
from embodichain_core.plugins.hookspecs import KINDS, PROJECT_NAME, new_registries
from embodichain_core.plugins.registry import Entry, NameClash, Registry, describe_target
from embodichain_core.utils.suggest import did_you_mean

ENTRY_POINT_GROUP = "embodichain"
BLOCK_ENV = "EMBODICHAIN_BLOCK_PLUGINS"
TRACE_ENV = "EMBODICHAIN_TRACE_PLUGINS"
#: Provider name of the core's own registrations.
CORE_PLUGIN_NAME = "embodichain-core"


class PluginLoadWarning(UserWarning):
    """A plugin failed to load and was skipped."""


class NameClashWarning(UserWarning):
    """A plugin task id that gymnasium already knows from outside the plugins (left as it is)."""


@dataclass
class PluginInfo:
    """One plugin as ``list_plugins()`` reports it; ``status``: loaded, failed or blocked."""

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
        lines = [line.strip() for line in self.error.splitlines() if line.strip()]
        return lines[-1] if lines else ""


class EmbodichainPluginManager(pluggy.PluginManager):
    """pluggy manager owning the registries; any ``embodichain_register*`` function is a hook
    (with or without ``@hookimpl``), so a misspelled one is caught."""

    def __init__(self) -> None:
        super().__init__(PROJECT_NAME)
        self.add_hookspecs(hookspecs)
        self.registries: dict[str, Registry] = new_registries()
        self.infos: dict[str, PluginInfo] = {}
        self.loaded = False
        self.lock = threading.RLock()
        self.tracing = os.environ.get(TRACE_ENV, "").strip() not in ("", "0")
        #: gym id -> the spec it had before this manager wrote it (None: absent).
        self.gym_saved: dict[str, Any] = {}
        self.gym_foreign: set[str] = set()  # ids gymnasium has from elsewhere, each reported once

    def parse_hookimpl_opts(self, plugin: Any, name: str) -> Any:
        opts = super().parse_hookimpl_opts(plugin, name)
        if opts is None and name.startswith("embodichain_register") and inspect.isroutine(getattr(plugin, name)):
            return {}
        return opts

    def registry(self, kind: str) -> Registry:
        """The registry of ``kind`` (``"functors"``, ``"robots"``, ...)."""
        if kind not in self.registries:
            raise ValueError(f"unknown registry kind {kind!r}.{did_you_mean(kind, list(KINDS))}")
        return self.registries[kind]

    def name_clashes(self, provider: str | None = None) -> list[NameClash]:
        """Bare names several plugins register, by kind then name (only ``provider``'s when given)."""
        found = [c for registry in self.registries.values() for c in registry.name_clashes()]
        return [c for c in found if provider is None or provider in c.providers]


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
    """Load the built-ins and (with ``entry_points``) the installed plugins but ``exclude``, once."""
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
            _register_entry_points(pm, exclude)
        for info in list(pm.infos.values()):
            if info.status == "loaded":
                try:
                    info.registered = _activate(pm, info.name)
                except Exception:
                    _fail(pm, info)
        pm.check_pending()
        sync_gym(pm)
    return pm


def _iter_entry_points() -> list[Any]:
    """Every ``"embodichain"`` entry point (a test seam)."""
    import importlib.metadata

    return list(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP))


def named_entry_points() -> list[tuple[str, Any]]:
    """``(plugin name, entry point)`` in load order: the distribution's (PEP 503-normalized)
    name, ``<dist>.<entry point>`` for a distribution with several."""
    eps = _iter_entry_points()
    norm = {id(ep): re.sub(r"[-_.]+", "-", getattr(getattr(ep, "dist", None), "name", "") or "").lower() for ep in eps}
    named = []
    for ep in eps:
        dist, own = norm[id(ep)], re.sub(r"[-_.]+", "-", ep.name).lower()
        alone = sum(norm[id(e)] == dist for e in eps) == 1 or own == dist
        named.append((ep.name if not dist else dist if alone else f"{dist}.{own}", ep))
    return sorted(named, key=lambda p: (p[0], p[1].name, str(getattr(p[1], "value", ""))))


def _register_entry_points(pm: EmbodichainPluginManager, exclude: frozenset[str]) -> None:
    blocked = {n.strip() for n in os.environ.get(BLOCK_ENV, "").split(",") if n.strip()}
    for name, ep in named_entry_points():
        if name in pm.infos or name in exclude:
            continue
        version = getattr(getattr(ep, "dist", None), "version", "") or ""
        info = pm.infos[name] = PluginInfo(name, version, module=ep.value, entry_point=ep.name)
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


def _fail(pm: EmbodichainPluginManager, info: PluginInfo) -> None:
    """Mark ``info`` failed and warn in one line."""
    info.status, info.error, info.registered = "failed", traceback.format_exc(), {}
    if pm.get_plugin(info.name) is not None:
        pm.unregister(name=info.name)
    exc = sys.exc_info()[1]
    first = (str(exc).strip().splitlines() or [""])[0]
    warnings.warn(
        f"embodichain plugin {info.name!r} failed to load and was skipped: {type(exc).__name__}: {first} "
        "(the traceback: `embodichain list plugins -v`, or embodichain_core.plugins.failed_plugins())",
        PluginLoadWarning,
        stacklevel=3,
    )


def _activate(pm: EmbodichainPluginManager, name: str) -> dict[str, list[str]]:
    """Run plugin ``name``'s hooks into staging registries, merged when all succeed; returns the
    names per kind. ``PluginValidationError`` for an unknown hook."""
    plugin = pm.get_plugin(name)
    for caller in pm.get_hookcallers(plugin) or []:
        if not caller.has_spec():
            known = [k.hook for k in KINDS.values()]
            message = f"plugin {name!r} implements unknown hook {caller.name!r}.{did_you_mean(caller.name, known)}"
            raise pluggy.PluginValidationError(plugin, message)
    staged = new_registries()
    for kind, spec in KINDS.items():
        for impl in getattr(pm.hook, spec.hook).get_hookimpls():
            if impl.plugin is plugin:
                if pm.tracing:
                    sys.stderr.write(f"embodichain plugins: {name}: {spec.hook}\n")
                register = spec.register(staged[kind], name)
                impl.function(*[register for _ in impl.argnames])
    for kind, registry in staged.items():
        for entry in registry.ordered_entries():
            pm.registries[kind].merge(entry)
    return {kind: [e.name for e in r.ordered_entries()] for kind, r in staged.items() if len(r)}


def register_plugin(obj: Any, name: str | None = None) -> str:
    """Register a plugin (module, class or instance) at runtime and run its hooks; returns its
    name. A failure raises and leaves nothing registered."""
    pm = load_plugins()
    with pm.lock:
        if name is None:
            cls = obj if inspect.isclass(obj) else type(obj)
            name = obj.__name__ if isinstance(obj, types.ModuleType) else f"{cls.__module__}.{cls.__qualname__}"
        if pm.register(obj, name=name) is None:
            raise ValueError(f"plugin {name!r} is blocked")
        try:
            registered = _activate(pm, name)
        except BaseException:
            pm.unregister(name=name)
            raise
        module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "")
        pm.infos[name] = PluginInfo(name, module=str(module), registered=registered)
        sync_gym(pm)
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
        sync_gym(pm)


@contextmanager
def isolated_plugins(
    *, load_entry_points: bool = False, exclude: Iterable[str] = ()
) -> Iterator[EmbodichainPluginManager]:
    """A fresh manager with the built-ins (and the installed plugins but ``exclude``); on exit the
    previous manager and the gymnasium ids it wrote are restored."""
    global _PM
    with _GLOBAL_LOCK:
        saved, _PM = _PM, EmbodichainPluginManager()
    try:
        yield load_plugins(entry_points=load_entry_points, exclude=frozenset(exclude))
    finally:
        with _GLOBAL_LOCK:
            pm, _PM = _PM, saved
        if pm is not None:
            sync_gym(pm, release=True)


def _ambiguous_task(registry: Registry, task_id: str, *args: Any, **kwargs: Any) -> Any:
    """gymnasium entry point of a bare id several plugins provide: raises the ambiguity error."""
    registry.entry(task_id)
    raise LookupError(f"task {task_id!r} is no longer ambiguous; make it again")


def _task_spec(pm: EmbodichainPluginManager, gym_id: str, entries: list[Entry]) -> Any:
    from embodichain_core.gym_vector import BatchedEnvSpec, make_vec_env

    target: Any = functools.partial(_ambiguous_task, pm.registries["tasks"], gym_id)
    vector, kwargs = target, {}
    if len(entries) == 1:
        target, kwargs = entries[0].target, dict(entries[0].meta["kwargs"])
        vector = functools.partial(make_vec_env, target)
    spec = BatchedEnvSpec(
        gym_id,
        entry_point=target,
        disable_env_checker=True,
        order_enforce=False,
        kwargs=kwargs,
        vector_entry_point=vector,
    )
    spec.embodichain_task = True  # type: ignore[attr-defined]
    return spec


def sync_gym(pm: EmbodichainPluginManager, *, release: bool = False) -> None:
    """Make gymnasium's registry show ``pm``'s tasks (none with ``release``) by qualified and
    bare id; an id gymnasium has from elsewhere is left as it is (a :class:`NameClashWarning`)."""
    tasks, wanted = pm.registries["tasks"], {}
    for entry in [] if release else tasks.ordered_entries():
        wanted[tasks.qualified_name(entry)] = [entry]
        wanted.setdefault(entry.name, []).append(entry)
    if not wanted and not pm.gym_saved:
        return  # a manager without tasks does not import gymnasium
    import gymnasium

    for gym_id in [g for g in pm.gym_saved if g not in wanted]:
        old = pm.gym_saved.pop(gym_id)
        if old is None:
            gymnasium.registry.pop(gym_id, None)
        else:
            gymnasium.registry[gym_id] = old
    for gym_id, entries in wanted.items():
        current = gymnasium.registry.get(gym_id)
        if gym_id not in pm.gym_saved and current is not None and not getattr(current, "embodichain_task", False):
            _report_foreign(pm, gym_id, current.entry_point, entries)
            continue
        pm.gym_saved.setdefault(gym_id, current)
        gymnasium.registry[gym_id] = _task_spec(pm, gym_id, entries)


def _report_foreign(pm: EmbodichainPluginManager, gym_id: str, theirs: Any, entries: list[Entry]) -> None:
    theirs, ours = describe_target(theirs), [e.target_repr for e in entries]
    if ours == [theirs] or f"{gym_id}={ours}" in pm.gym_foreign:
        return  # the same class, registered by its own module; or reported already
    pm.gym_foreign.add(f"{gym_id}={ours}")
    ids = ", ".join(repr(pm.registries["tasks"].qualified_name(e)) for e in entries)
    warnings.warn(
        f"gymnasium id {gym_id!r} is already registered outside the embodichain plugins (entry point "
        f"{theirs!r}); it is left as it is. Use {ids} for the plugin task{'s' if len(entries) > 1 else ''}.",
        NameClashWarning,
        stacklevel=3,
    )


def list_plugins() -> list[PluginInfo]:
    """Every known plugin (loaded, failed or blocked), in load order."""
    return list(load_plugins().infos.values())


def failed_plugins() -> list[tuple[str, str]]:
    """``(name, traceback)`` of the plugins that failed to load."""
    return [(i.name, i.error) for i in load_plugins().infos.values() if i.status == "failed"]


def known_providers() -> set[str]:
    """Names of every known plugin (loaded, failed or blocked)."""
    return set(load_plugins().infos)


def get_registry(kind: str) -> Registry:
    """The registry of ``kind`` (loads plugins first)."""
    return load_plugins().registry(kind)
