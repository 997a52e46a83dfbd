"""Shared machinery of the managers: validating a section before the build
(:meth:`ManagerBase.validate_section`, each manager adding its own rules), building its
functors, tagging the errors they raise with their config path."""

from __future__ import annotations

import copy
import inspect
import sys
from dataclasses import dataclass
from typing import Any, Generic, Optional, TypeVar

from embodichain_core.config.checks import describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import FunctorCfg
from embodichain_core.managers.functor import Functor
from embodichain_core.managers.entity_params import check_entity_params, entity_params
from embodichain_core.managers.param_rules import (
    check_data_paths,
    check_named_params,
    check_param_types,
    check_signature,
)
from embodichain_core.managers.resolution import iter_section, resolve_entities, resolve_func, resolve_functor
from embodichain_core.utils.configclass import MISSING
from embodichain_core.utils.suggest import closest, did_you_mean

__all__ = [
    "ValidatedFunctor",
    "BuiltFunctor",
    "ManagerBase",
    "OWN_SECTION",
    "functor_path_of",
    "is_checked",
    "iter_section",
    "resolve_func",
    "resolve_functor",
    "tag_functor_error",
]

CfgT = TypeVar("CfgT", bound=FunctorCfg)


@dataclass
class BuiltFunctor(Generic[CfgT]):
    """A functor as its manager calls it: built from a :class:`ValidatedFunctor` when the
    manager is made (a class functor instantiated; ``cfg`` is the manager's functor cfg type,
    its entity params resolved). Calling it calls ``func(*args, **cfg.params)``."""

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


@dataclass(frozen=True)
class ValidatedFunctor(Generic[CfgT]):
    """One entry of a manager section that passed :meth:`ManagerBase.validate_section`:
    checked and resolved, not built yet (the manager builds a :class:`BuiltFunctor` from it).

    Attributes:
        name: the entry's key in its section.
        path: its config path (``env.events.fork_mass``).
        cfg: the entry as configured (``func`` as given).
        func: the resolved function or class.
        entry: the plugin registry's :class:`~embodichain_core.plugins.registry.RegistryEntry`
            when ``func`` was given by a registered name, else ``None``.
        entities: the params naming scene entities -> whether each takes a list of them.
    """

    name: str
    path: str
    cfg: CfgT
    func: Any
    entry: Any
    entities: dict[str, bool]


def is_checked(section: Any) -> bool:
    """True for a section :meth:`ManagerBase.validate_section` returned."""
    return isinstance(section, dict) and all(isinstance(v, ValidatedFunctor) for v in section.values())


#: ``validate_section``'s default: the manager's own section of the env config.
OWN_SECTION: Any = object()


class ManagerBase(Generic[CfgT]):
    """Validates and builds the functors of one config section.

    Subclasses set ``section`` (the config key), ``kind`` (functor kind in the
    registry), ``cfg_type``, ``min_argc`` (positional args before the params; ``None``:
    the params go to the class's constructor) and ``modes``, and parametrize the class
    with their cfg type (``ManagerBase[EventCfg]``). Their own rules go in
    :meth:`check_entry` (one entry) and :meth:`check_entries` (the whole section).
    """

    section = ""
    kind = ""
    cfg_type: type = FunctorCfg
    min_argc: Optional[int] = 2
    modes: tuple[str, ...] = ()

    def __init__(self, cfg: Any, env: Any, path: Optional[str] = None):
        """Build the functors of ``cfg``: a section :meth:`validate_section` returned (the
        env's build), or a section as configured (validated first against ``env.cfg``)."""
        self._env = env
        self.path = path or f"env.{self.section}"
        if not is_checked(cfg):
            uids = getattr(getattr(env, "scene", None), "asset_uids", None)
            cfg = self.validate_section(getattr(env, "cfg", None), cfg, uids=uids, path=self.path, warn=True)
        self.entries: dict[str, BuiltFunctor[CfgT]] = {n: self._build_functor(c) for n, c in cfg.items()}

    @classmethod
    def validate_section(
        cls,
        env_cfg: Any,
        section: Any = OWN_SECTION,
        *,
        uids: Optional[list[str]] = None,
        path: Optional[str] = None,
        warn: bool = False,
    ) -> dict[str, ValidatedFunctor[CfgT]]:
        """Check every entry of this manager's section, before anything is built.

        Each ``func`` is resolved (once: the env builds from the result), its params are
        checked against its signature and the rules of :mod:`.param_rules`, entity params
        against ``uids``, and the entry against the manager's own rules (modes...).

        Args:
            env_cfg: the env config (may be ``None``): its section, unless ``section`` is
                given, and the settings the rules read (``custom_event_modes``...).
            section: the section to check instead of ``env_cfg.<section>``.
            uids: the scene's entity uids (``None``: entity uids are checked at the build).
            path: the section's config path (default ``env.<section>``).
            warn: warn about valid values that look like mistakes.

        Returns:
            ``{name: ValidatedFunctor}`` in config order.

        Raises:
            ConfigError: at the config path of the first bad value.
        """
        path = path or join_path("env", cls.section)
        if section is OWN_SECTION:
            section = getattr(env_cfg, cls.section, None)
        checked: dict[str, ValidatedFunctor[CfgT]] = {}
        for name, fcfg in iter_section(section, cls.cfg_type, path):
            checked[name] = cls._check_functor(name, fcfg, join_path(path, name), uids)
            cls.check_entry(checked[name], env_cfg, warn)
        cls.check_entries(checked, path)
        return checked

    @classmethod
    def _check_functor(cls, name: str, fcfg: Any, where: str, uids: Optional[list[str]]) -> ValidatedFunctor:
        """The rules every section shares: ``func`` resolves, the params fit it."""
        given = fcfg.func
        if given is None or isinstance(given, type(MISSING)) or (isinstance(given, str) and not given.strip()):
            raise ConfigError(join_path(where, "func"), "missing 'func' (a registered functor name or 'module:attr')")
        if not isinstance(given, str) and not callable(given):
            raise ConfigError(join_path(where, "func"), f"expected a functor name or a callable, got {describe(given)}")
        func, entry = resolve_functor(given, cls.kind, where)
        if inspect.isclass(func) and not issubclass(func, Functor):
            raise ConfigError(f"{where}.func", f"class {func.__name__} must subclass Functor")
        params = fcfg.params
        if not isinstance(params, dict):
            raise ConfigError(join_path(where, "params"), f"expected a mapping of params, got {describe(params)}")
        label = getattr(func, "__name__", type(func).__name__)
        if cls.min_argc is not None:
            check_signature(func, params, cls.min_argc, where)
            check_param_types(func, params, where, cls.min_argc)
        check_named_params(params, where, label)
        check_data_paths(func, params, where, cls.min_argc)
        entities = entity_params(func, cls.min_argc, params)
        check_entity_params(params, entities, join_path(where, "params"), uids)
        return ValidatedFunctor(name, where, fcfg, func, entry, entities)

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """The manager's own rules for one entry (by default: its ``mode``)."""
        cls.check_mode(checked.cfg.mode, checked.path)

    @classmethod
    def check_entries(cls, checked: dict[str, ValidatedFunctor], path: str) -> None:
        """The manager's rules across the entries of its section (none by default)."""

    @classmethod
    def check_mode(cls, mode: Any, where: str) -> None:
        """``mode`` is one of :attr:`modes` (a typo gets the suggestion)."""
        if mode in cls.modes:
            return
        hint = did_you_mean(mode, cls.modes) if isinstance(mode, str) and closest(mode, cls.modes) else ""
        choices = " or ".join(map(repr, cls.modes))
        raise ConfigError(join_path(where, "mode"), f"mode must be {choices}, got {describe(mode)}.{hint}")

    def _build_functor(self, checked: ValidatedFunctor) -> BuiltFunctor[CfgT]:
        cfg, func, where = copy.deepcopy(checked.cfg), checked.func, checked.path
        cfg.params = resolve_entities(dict(cfg.params), self._env.scene, join_path(where, "params"), checked.entities)
        cfg.func = func
        self._run_param_check(func, cfg, where)
        is_class = inspect.isclass(func)
        if is_class:
            try:
                func = func(cfg=cfg, env=self._env)
            except ConfigError as err:  # a path relative to the functor ("params.x") gets its entry's
                if err.path == "params" or err.path.startswith(("params.", "params[")):
                    raise err.under(where) from err
                raise
            except Exception as err:
                raise ConfigError(where, f"building functor {cfg.func.__name__} failed: {err}") from err
        return BuiltFunctor(checked.name, cfg, func, is_class, where)

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


def _func_name(entry: BuiltFunctor) -> str:
    func = entry.cfg.func
    return getattr(func, "__name__", type(func).__name__)
