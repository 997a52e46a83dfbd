"""Shared machinery of the managers: reading a config section, resolving functors,
checking their params against their signatures, resolving ``SceneEntityCfg``."""

from __future__ import annotations

import copy
import dataclasses
import importlib
import inspect
import sys
from dataclasses import dataclass
from typing import Any, Generic, Iterator, Optional, TypeVar

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import FunctorCfg, SceneEntityCfg
from embodichain_core.managers.functor import Functor
from embodichain_core.utils.configclass import MISSING, is_configclass
from embodichain_core.utils.suggest import did_you_mean

ENTITY_PARAM_KEYS = {
    "entity_cfg",
    "source_entity_cfg",
    "target_entity_cfg",
    "object_cfg",
    "goal_cfg",
    "reference_entity_cfg",
    "end_effector_cfg",
    "robot_cfg",
    "obj_a_cfg",
    "obj_b_cfg",
}


CfgT = TypeVar("CfgT", bound=FunctorCfg)


@dataclass
class FunctorEntry(Generic[CfgT]):
    """One resolved functor of a manager (``cfg`` is the manager's functor cfg type)."""

    name: str
    cfg: CfgT
    func: Any
    is_class: bool
    path: str

    def __call__(self, *args: Any) -> Any:
        try:
            return self.func(*args, **self.cfg.params)
        except Exception as err:
            tag_functor_error(err, self.path, self.func)
            raise


#: Attribute set on an exception raised inside a functor: the functor's config path.
FUNCTOR_PATH_ATTR = "embodichain_functor_path"


def tag_functor_error(err: BaseException, path: str, func: Any) -> None:
    """Mark ``err`` (raised inside a functor) with the functor's config path.

    The innermost functor wins: an event functor calling another functor keeps the
    inner path. The exception's type is unchanged; a note names the functor, so a
    printed traceback ends with ``raised in functor env.events.drive_damping (...)``.
    """
    if functor_path_of(err) is not None:
        return
    try:
        setattr(err, FUNCTOR_PATH_ATTR, path)
    except AttributeError:  # exceptions with __slots__
        return
    name = getattr(func, "__name__", None) or type(func).__name__
    note = f"raised in functor {path} ({name})"
    if sys.version_info >= (3, 11):
        err.add_note(note)
    else:  # Python 3.10 has no add_note (nor prints notes): keep the note where 3.11 would
        setattr(err, "__notes__", [*getattr(err, "__notes__", []), note])


def functor_path_of(err: BaseException) -> Optional[str]:
    """The config path of the functor that raised ``err`` (``None`` when none did)."""
    return getattr(err, FUNCTOR_PATH_ATTR, None)


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
    if func is None or isinstance(func, type(MISSING)):  # a deep-copied cfg holds a copy of MISSING
        raise ConfigError(f"{path}.func", "no 'func' given")
    if not isinstance(func, str):
        if not callable(func):
            raise ConfigError(f"{path}.func", f"{func!r} is not callable")
        return func
    from embodichain_core.plugins.manager import known_providers

    if ":" not in func:
        return _from_registry(func, kind, path)
    module, _, attr = func.partition(":")
    try:
        obj = importlib.import_module(module)
        for part in attr.split("."):
            obj = getattr(obj, part)
        return obj
    except (ImportError, AttributeError) as err:
        hint = f" ({module!r} is a plugin: its functor {attr!r} is written {module + '/' + attr!r})"
        hint = hint if module in known_providers() else ""
        raise ConfigError(f"{path}.func", f"cannot import {func!r}: {err}{hint}") from err


def _from_registry(name: str, kind: str, path: str) -> Any:
    """The functor registered as ``name`` (bare or ``"<plugin>/<name>"``); errors name
    the config path, and suggest functors of the same ``kind``."""
    from embodichain_core.plugins import AmbiguousNameError, get_registry

    registry = get_registry("functors")
    try:
        entry = registry.find(name)
    except AmbiguousNameError as err:
        raise ConfigError(f"{path}.func", str(err)) from None
    if entry is not None:
        return entry.resolve()
    if "/" in name:
        raise ConfigError(f"{path}.func", str(registry.unknown(name)))
    same_kind = [e.name for e in registry.entries() if e.meta.get("kind") == kind] or registry.names()
    hint = did_you_mean(name, same_kind) or " No functor plugin registers it (is the plugin installed?)."
    raise ConfigError(f"{path}.func", f"unknown {kind} functor {name!r}.{hint}")


def check_params(func: Any, params: dict, min_argc: int, path: str) -> None:
    """Unknown params and missing required params are errors naming the functor."""
    target = func.__call__ if inspect.isclass(func) else func
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return
    args = [p for p in sig.parameters.values() if p.name != "self"]
    if any(p.kind is p.VAR_KEYWORD for p in args):
        allowed = None
    else:
        allowed = {p.name for p in args[min_argc:] if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    required = [
        p.name for p in args[min_argc:] if p.default is p.empty and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
    ]
    name = getattr(func, "__name__", repr(func))
    if allowed is not None:
        for key in params:
            if key not in allowed:
                raise ConfigError(
                    join_path(path, "params", key),
                    f"functor {name!r} has no parameter {key!r}.{did_you_mean(key, allowed)}",
                )
    missing = [r for r in required if r not in params]
    if missing:
        raise ConfigError(join_path(path, "params"), f"functor {name!r} needs parameter(s) {missing}")


def check_ranges(params: dict, path: str, name: str) -> None:
    """Params checked by naming convention (``*_range`` pairs with low <= high, colour
    ranges in [0, 1], ``*_prob`` in [0, 1], ...): see :mod:`.param_rules`."""
    from embodichain_core.managers.param_rules import check_named_params

    check_named_params(params, path, name)


def resolve_entities(value: Any, scene: Any, path: str, key: str = "") -> Any:
    """Resolve every ``SceneEntityCfg`` (or entity dict) anywhere in ``value``."""
    if isinstance(value, SceneEntityCfg):
        return value.resolve(scene, path)
    if isinstance(value, dict):
        if (key in ENTITY_PARAM_KEYS or key.endswith("entity_cfg")) and "uid" in value:
            return SceneEntityCfg.from_dict(value, path).resolve(scene, path)
        return {k: resolve_entities(v, scene, join_path(path, k), k) for k, v in value.items()}
    if isinstance(value, list):
        return [resolve_entities(v, scene, f"{path}[{i}]", key) for i, v in enumerate(value)]
    if isinstance(value, tuple):
        return tuple(resolve_entities(v, scene, f"{path}[{i}]", key) for i, v in enumerate(value))
    return value


class ManagerBase(Generic[CfgT]):
    """Builds the functors of one config section.

    Subclasses set ``section`` (the config key), ``kind`` (functor kind in the
    registry), ``cfg_type`` and ``min_argc`` (positional args before params), and
    parametrize the class with their cfg type (``ManagerBase[EventCfg]``).
    """

    section = ""
    kind = ""
    cfg_type: type = FunctorCfg
    min_argc = 2

    def __init__(self, cfg: Any, env: Any, path: Optional[str] = None):
        self._env = env
        self.path = path or f"env.{self.section}"
        self.entries: dict[str, FunctorEntry[CfgT]] = {}
        for name, fcfg in iter_section(cfg, self.cfg_type, self.path):
            self.entries[name] = self._build_entry(name, copy.deepcopy(fcfg))

    def _build_entry(self, name: str, cfg: CfgT) -> FunctorEntry[CfgT]:
        where = join_path(self.path, name)
        func = resolve_func(cfg.func, self.kind, where)
        is_class = inspect.isclass(func)
        if is_class and not issubclass(func, Functor):
            raise ConfigError(f"{where}.func", f"class {func.__name__} must subclass Functor")
        self._check(func, cfg, where)
        cfg.params = resolve_entities(dict(cfg.params), self._env.scene, join_path(where, "params"))
        cfg.func = func
        self._run_param_check(func, cfg, where)
        if is_class:
            try:
                func = func(cfg=cfg, env=self._env)
            except ConfigError as err:  # a path relative to the functor ("params.x") gets its entry's
                if err.path == "params" or err.path.startswith(("params.", "params[")):
                    raise err.under(where) from err
                raise
            except Exception as err:
                raise ConfigError(where, f"building functor {cfg.func.__name__} failed: {err}") from err
        return FunctorEntry(name, cfg, func, is_class, where)

    def _run_param_check(self, func: Any, cfg: CfgT, where: str) -> None:
        """A function functor may carry ``check_params(env, **params)``; it runs
        now, so bad values are reported when the manager is built."""
        hook = getattr(func, "check_params", None)
        if inspect.isclass(func) or not callable(hook):
            return
        try:
            hook(self._env, **cfg.params)
        except ConfigError as err:
            param = getattr(err, "param", None)  # errors naming the param they are about
            if param is not None:
                raise ConfigError(join_path(where, "params", param), err.reason) from err
            raise err if err.path.startswith(where) else err.under(join_path(where, "params"))
        except (TypeError, ValueError) as err:
            raise ConfigError(join_path(where, "params"), f"{getattr(func, '__name__', func)}: {err}") from err

    def _check(self, func: Any, cfg: CfgT, where: str) -> None:
        check_params(func, cfg.params, self.min_argc, where)
        check_ranges(cfg.params, where, getattr(func, "__name__", str(func)))

    @property
    def active_functors(self) -> list[str]:
        return list(self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def get_functor(self, name: str) -> Any:
        if name not in self.entries:
            raise KeyError(f"{self.section}: no functor {name!r}.{did_you_mean(name, self.entries)}")
        return self.entries[name].func

    def get_functor_cfg(self, name: str) -> CfgT:
        self.get_functor(name)
        return self.entries[name].cfg

    def reset(self, env_ids: Any = None) -> dict:
        """Call ``reset(env_ids)`` on every class functor."""
        for entry in self.entries.values():
            if entry.is_class:
                entry.func.reset(env_ids)
        return {}

    def summary_rows(self) -> list[tuple[str, str, str]]:
        """(mode, name, detail) rows for the construction summary."""
        return [(getattr(e.cfg, "mode", ""), n, _func_name(e)) for n, e in self.entries.items()]


def _func_name(entry: FunctorEntry) -> str:
    func = entry.cfg.func
    return getattr(func, "__name__", type(func).__name__)
