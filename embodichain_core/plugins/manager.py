"""The plugin host: loads the core's and the installed plugins (entry point group
``"embodichain"``, sorted by plugin name), fills the registries and writes the tasks into
gymnasium. A plugin that fails contributes nothing (what its hooks registered is removed) and is
reported in one line (:class:`PluginLoadWarning`)."""

from __future__ import annotations

import functools
import importlib.metadata
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
from embodichain_core.plugins.hookspecs import KINDS, PROJECT_NAME, hook_name, new_registries
from embodichain_core.plugins.registry import RegistryEntry, Registry, describe_target, join_names
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
        return next((line.strip() for line in reversed(self.error.splitlines()) if line.strip()), "")


@dataclass(frozen=True)
class NameClash:
    """A bare name several plugins register: its ``providers`` and ``qualified`` names."""

    kind: str
    name: str
    providers: tuple[str, ...]
    qualified: tuple[str, ...]

    def __str__(self) -> str:
        forms = join_names(self.qualified, "or")
        return f"{self.kind.removesuffix('s')} {self.name!r} is provided by {join_names(self.providers)} (use {forms})"


class EmbodichainPluginManager(pluggy.PluginManager):
    """pluggy manager owning the registries and the gymnasium specs it wrote."""

    def __init__(self) -> None:
        super().__init__(PROJECT_NAME)
        self.add_hookspecs(hookspecs)
        self.registries: dict[str, Registry] = new_registries()
        self.infos: dict[str, PluginInfo] = {}
        self.loaded = False
        self.gym_specs: dict[str, Any] = {}

    def registry(self, kind: str) -> Registry:
        """The registry of ``kind`` (``"functors"``, ``"robots"``, ...)."""
        if kind not in self.registries:
            raise ValueError(f"unknown registry kind {kind!r}.{did_you_mean(kind, list(KINDS))}")
        return self.registries[kind]

    def name_clashes(self, provider: str | None = None) -> list[NameClash]:
        """Bare names several plugins register, by kind then name (only ``provider``'s when given)."""
        return [
            NameClash(kind, name, tuple(found), tuple(r.qualified_name(r.entry(f"{p}/{name}")) for p in found))
            for kind, r in self.registries.items()
            for name, found in r.clashes().items()
            if provider is None or provider in found
        ]


_PM: EmbodichainPluginManager | None = None
_LOCK = threading.RLock()  # guards the current manager and its loading


def get_plugin_manager() -> EmbodichainPluginManager:
    """The current plugin manager (created on first call; plugins not loaded yet)."""
    global _PM
    with _LOCK:
        if _PM is None:
            _PM = EmbodichainPluginManager()
        return _PM


def load_plugins(*, entry_points: bool = True, exclude: frozenset[str] = frozenset()) -> EmbodichainPluginManager:
    """Load the built-ins and (with ``entry_points``) the installed plugins but ``exclude``, once."""
    pm = get_plugin_manager()
    with _LOCK:
        if pm.loaded:
            return pm
        pm.loaded = True
        from embodichain_core import __version__
        from embodichain_core.plugins import builtin

        pm.register(builtin, name=CORE_PLUGIN_NAME)
        pm.infos[CORE_PLUGIN_NAME] = PluginInfo(CORE_PLUGIN_NAME, __version__, module=builtin.__name__)
        if entry_points:
            _register_entry_points(pm, exclude)
        for info in [i for i in pm.infos.values() if i.status == "loaded"]:
            try:
                info.registered = _activate(pm, info.name)
            except Exception:
                _fail(pm, info)
        sync_gym(pm)
    return pm


def named_entry_points() -> list[tuple[str, Any]]:
    """``(plugin name, entry point)`` of the ``"embodichain"`` entry points in load order. A plugin
    is named after its distribution (PEP 503-normalized), ``<dist>.<entry point>`` when the
    distribution has several."""

    def norm(name: str) -> str:
        return re.sub(r"[-_.]+", "-", name).lower()

    eps = list(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP))
    dists = [norm(getattr(getattr(ep, "dist", None), "name", "") or "") for ep in eps]
    named = [
        (dist if dists.count(dist) == 1 or norm(ep.name) == dist else f"{dist}.{norm(ep.name)}") if dist else ep.name
        for ep, dist in zip(eps, dists)
    ]
    return sorted(zip(named, eps), key=lambda p: (p[0], p[1].name, str(getattr(p[1], "value", ""))))


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
    """Mark ``info`` failed (in an ``except`` block) and warn in one line."""
    info.status, info.error, info.registered = "failed", traceback.format_exc(), {}
    _drop(pm, info.name)
    exc = sys.exc_info()[1]
    first = (str(exc).strip().splitlines() or [""])[0]
    warnings.warn(
        f"embodichain plugin {info.name!r} failed to load and was skipped: {type(exc).__name__}: {first} "
        "(the traceback: `embodichain list plugins -v`, or embodichain_core.plugins.failed_plugins())",
        PluginLoadWarning,
        stacklevel=3,
    )


def _activate(pm: EmbodichainPluginManager, name: str) -> dict[str, list[str]]:
    """Run plugin ``name``'s hooks (``PluginValidationError`` for an unknown hook); returns the
    names it registered per kind. On a failure the caller removes the plugin (:func:`_drop`)."""
    plugin = pm.get_plugin(name)
    for caller in pm.get_hookcallers(plugin) or []:
        if not caller.has_spec():
            hint = did_you_mean(caller.name, [hook_name(kind) for kind in KINDS])
            raise pluggy.PluginValidationError(
                plugin, f"plugin {name!r} implements unknown hook {caller.name!r}.{hint}"
            )
    trace = os.environ.get(TRACE_ENV, "").strip() not in ("", "0")
    for kind, register in KINDS.items():
        for impl in getattr(pm.hook, hook_name(kind)).get_hookimpls():
            if impl.plugin is plugin:
                if trace:
                    sys.stderr.write(f"embodichain plugins: {name}: {hook_name(kind)}\n")
                impl.function(*[register(pm.registries[kind], name) for _ in impl.argnames])
    found = {kind: [e.name for e in r.ordered_entries() if e.provider == name] for kind, r in pm.registries.items()}
    return {kind: names for kind, names in found.items() if names}


def _drop(pm: EmbodichainPluginManager, name: str) -> None:
    """Remove plugin ``name`` from ``pm`` and its entries from the registries."""
    for registry in pm.registries.values():
        registry.drop(name)
    if pm.get_plugin(name) is not None:
        pm.unregister(name=name)


def register_plugin(obj: Any, name: str | None = None) -> str:
    """Register a plugin (module, class or instance) at runtime and run its hooks; returns its
    name. A failure raises and leaves nothing registered."""
    pm = load_plugins()
    with _LOCK:
        if name is None:
            cls = obj if inspect.isclass(obj) else type(obj)
            name = obj.__name__ if isinstance(obj, types.ModuleType) else f"{cls.__module__}.{cls.__qualname__}"
        if pm.register(obj, name=name) is None:
            raise ValueError(f"plugin {name!r} is blocked")
        try:
            registered = _activate(pm, name)
        except BaseException:
            _drop(pm, name)
            raise
        module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "")
        pm.infos[name] = PluginInfo(name, module=str(module), registered=registered)
        sync_gym(pm)
    return name


def unregister_plugin(name: str) -> None:
    """Remove plugin ``name`` and everything it registered."""
    pm = load_plugins()
    with _LOCK:
        _drop(pm, name)
        pm.infos.pop(name, None)
        sync_gym(pm)


@contextmanager
def isolated_plugins(
    *, load_entry_points: bool = False, exclude: Iterable[str] = ()
) -> Iterator[EmbodichainPluginManager]:
    """A fresh manager with the built-ins (and the installed plugins but ``exclude``); on exit the
    previous manager is current again, with its gymnasium ids."""
    global _PM
    with _LOCK:
        saved, _PM = _PM, EmbodichainPluginManager()
    try:
        yield load_plugins(entry_points=load_entry_points, exclude=frozenset(exclude))
    finally:
        with _LOCK:
            pm, _PM = _PM, saved
        for manager, release in ((pm, True), (saved, False)):
            if manager is not None:
                sync_gym(manager, release=release)


def _make_task(registry: Registry, task_id: str, *args: Any, **kwargs: Any) -> Any:
    """The gymnasium entry point of a bare id several plugins register: making it raises the
    :class:`AmbiguousNameError` naming the qualified ids."""
    return registry.get(task_id)(*args, **kwargs)


def _task_spec(pm: EmbodichainPluginManager, gym_id: str, entries: list[RegistryEntry]) -> Any:
    from embodichain_core.gym_vector import BatchedEnvSpec, make_vec_env

    target: Any = functools.partial(_make_task, pm.registries["tasks"], gym_id)
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
    spec.embodichain_task, spec.embodichain_entries = True, entries  # type: ignore[attr-defined]
    return spec


def sync_gym(pm: EmbodichainPluginManager, *, release: bool = False) -> None:
    """Make gymnasium's registry show ``pm``'s tasks (none with ``release``) by qualified and bare
    id, removing the ids ``pm`` wrote that it no longer has; an id gymnasium has from elsewhere is
    left as it is (a :class:`NameClashWarning` unless it names the same class)."""
    import gymnasium

    tasks, wanted = pm.registries["tasks"], {}
    for entry in [] if release else tasks.ordered_entries():
        wanted[tasks.qualified_name(entry)] = [entry]
        wanted.setdefault(entry.name, []).append(entry)
    for gym_id in [g for g in pm.gym_specs if g not in wanted]:
        if gymnasium.registry.get(gym_id) is pm.gym_specs.pop(gym_id):
            del gymnasium.registry[gym_id]
    for gym_id, entries in wanted.items():
        current = gymnasium.registry.get(gym_id)
        if current is not None and not getattr(current, "embodichain_task", False):
            theirs, ids = describe_target(current.entry_point), [tasks.qualified_name(e) for e in entries]
            if [e.target_repr for e in entries] != [theirs]:
                warnings.warn(
                    f"gymnasium id {gym_id!r} is already registered outside the embodichain plugins (entry point "
                    f"{theirs!r}); it is left as it is. Use {join_names(ids)} for the plugin task"
                    f"{'s' if len(ids) > 1 else ''}.",
                    NameClashWarning,
                    stacklevel=3,
                )
            continue
        if getattr(pm.gym_specs.get(gym_id), "embodichain_entries", None) != entries:
            pm.gym_specs[gym_id] = _task_spec(pm, gym_id, entries)
        gymnasium.registry[gym_id] = pm.gym_specs[gym_id]


def list_plugins() -> list[PluginInfo]:
    """Every known plugin (loaded, failed or blocked), in load order."""
    return list(load_plugins().infos.values())


def failed_plugins() -> list[tuple[str, str]]:
    """``(name, traceback)`` of the plugins that failed to load."""
    return [(i.name, i.error) for i in list_plugins() if i.status == "failed"]


def get_registry(kind: str) -> Registry:
    """The registry of ``kind`` (loads plugins first)."""
    return load_plugins().registry(kind)
