"""How a manager section's entries become callables: reading a section, resolving
``func`` (a callable, a registered name or a ``"module:attr"`` path) and the
``SceneEntityCfg`` params."""

from __future__ import annotations

import dataclasses
from typing import Any, Iterator

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import FunctorCfg, SceneEntityCfg
from embodichain_core.utils.configclass import MISSING, is_configclass
from embodichain_core.utils.suggest import did_you_mean

__all__ = ["iter_section", "resolve_func", "resolve_functor", "resolve_entities"]


def iter_section(section: Any, cfg_type: type[FunctorCfg], path: str) -> Iterator[tuple[str, Any]]:
    """Yield ``(name, functor cfg)`` of a manager section (config object or dict)."""
    if section is None:
        return
    if isinstance(section, dict):
        items = list(section.items())
    elif is_configclass(section):
        items = [(f.name, getattr(section, f.name)) for f in dataclasses.fields(section)]
    else:
        items = [(k, v) for k, v in vars(section).items() if not k.startswith("_")]
    for name, value in items:
        where = join_path(path, name)
        if value is None:
            continue
        if isinstance(value, dict):
            if "func" not in value:
                continue  # plain metadata next to functors (e.g. dataset robot_meta)
            value = cfg_type.from_dict(value, where)
        if not isinstance(value, FunctorCfg):
            raise ConfigError(where, f"expected a {cfg_type.__name__}, got {type(value).__name__}")
        yield name, value


def resolve_func(func: Any, kind: str, path: str) -> Any:
    """A functor from a callable, a registered name or a ``"module:attr"`` import path.

    A string is read by one rule, whatever is installed: a string with a ``:`` is a
    ``"module:attr"`` import path; ``"<plugin>/<name>"``
    (``"embodichain-functors/randomize_light"``) is a qualified registered name; any other
    string is a bare registered name (an error naming every provider when several plugins
    register it).
    """
    return resolve_functor(func, kind, path)[0]


def resolve_functor(func: Any, kind: str, path: str) -> tuple[Any, Any]:
    """``(functor, registry entry)`` of ``func`` as :func:`resolve_func` reads it; the
    entry is ``None`` for a callable or an import path."""
    if func is None or isinstance(func, type(MISSING)):  # a deep-copied cfg holds a copy of MISSING
        raise ConfigError(f"{path}.func", "no 'func' given")
    if not isinstance(func, str):
        if not callable(func):
            raise ConfigError(f"{path}.func", f"{func!r} is not callable")
        return func, None
    from embodichain_core.plugins import list_plugins
    from embodichain_core.plugins.registry import import_target

    if ":" not in func:
        entry = _from_registry(func, kind, path)
        return entry.resolve(), entry
    module, _, attr = func.partition(":")
    try:
        return import_target(func), None
    except (ImportError, AttributeError) as err:
        hint = f" ({module!r} is a plugin: its functor {attr!r} is written {module + '/' + attr!r})"
        hint = hint if module in {p.name for p in list_plugins()} else ""
        raise ConfigError(f"{path}.func", f"cannot import {func!r}: {err}{hint}") from err


def _from_registry(name: str, kind: str, path: str) -> Any:
    """The registry entry of the functor ``name`` (bare or ``"<plugin>/<name>"``); errors
    name the config path, and suggest functors of the same ``kind``."""
    from embodichain_core.plugins import AmbiguousNameError, get_registry

    registry = get_registry("functors")
    try:
        entry = registry.find(name)
    except AmbiguousNameError as err:
        raise ConfigError(f"{path}.func", str(err)) from None
    if entry is not None:
        return entry
    if "/" in name:
        raise ConfigError(f"{path}.func", str(registry.unknown(name)))
    same_kind = [e.name for e in registry.entries() if e.meta.get("kind") == kind] or registry.names()
    hint = did_you_mean(name, same_kind) or " No functor plugin registers it (is the plugin installed?)."
    raise ConfigError(f"{path}.func", f"unknown {kind} functor {name!r}.{hint}")


def resolve_entities(params: dict, scene: Any, path: str, entities: dict[str, bool]) -> dict:
    """``params`` with the entity params (see :func:`~.entity_params.entity_params`) as
    resolved ``SceneEntityCfg`` (a ``{"uid": ...}`` mapping becomes one), and every
    ``SceneEntityCfg`` found anywhere else in the params resolved too."""
    out = {}
    for key, value in params.items():
        where = join_path(path, key)
        if key in entities and entities[key] and isinstance(value, (list, tuple)):
            out[key] = type(value)(_entity(v, scene, f"{where}[{i}]") for i, v in enumerate(value))
        elif key in entities:
            out[key] = _entity(value, scene, where)
        else:
            out[key] = _nested(value, scene, where)
    return out


def _entity(value: Any, scene: Any, path: str) -> Any:
    if isinstance(value, dict):
        value = SceneEntityCfg.from_dict(value, path)
    return _nested(value, scene, path)


def _nested(value: Any, scene: Any, path: str) -> Any:
    if isinstance(value, SceneEntityCfg):
        return value.resolve(scene, path)
    if isinstance(value, dict):
        return {k: _nested(v, scene, join_path(path, k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_nested(v, scene, f"{path}[{i}]") for i, v in enumerate(value))
    return value
