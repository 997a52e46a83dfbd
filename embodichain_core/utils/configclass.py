"""``@configclass``: dataclasses for configuration, with strict dict round trips.

A config class is a dataclass whose every field has a default:

* members without an annotation get ``type(default)`` as their annotation, so a
  subclass may override a field with a bare ``events = MyEventCfg()``;
* mutable defaults (lists, dicts, nested configs) are deep-copied per instance;
* ``MISSING`` marks a required field; ``validate()`` lists the ones still unset;
* ``to_dict()`` / ``from_dict()`` convert to and from plain data. Unknown keys and
  wrong types raise :class:`~embodichain_core.config.errors.ConfigError` naming the
  path of the entry and the closest valid key.

Example:
    >>> @configclass
    ... class ArmCfg:
    ...     uid: str = MISSING
    ...     init_pos: tuple = (0.0, 0.0, 0.0)
    >>> ArmCfg.from_dict({"uid": "arm", "init_pos": [0, 0, 1]}).init_pos
    (0, 0, 1)
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import sys
from typing import Any, Callable, ClassVar, Protocol, TypeVar

from embodichain_core.config.convert import convert_value, to_plain
from embodichain_core.config.errors import ConfigError, join_path, unknown_key

if sys.version_info >= (3, 11):
    from typing import dataclass_transform
else:  # Python 3.10: the typing_extensions backport (a dependency on 3.10)
    from typing_extensions import dataclass_transform

__all__ = ["configclass", "MISSING", "is_configclass", "ConfigClass"]

T = TypeVar("T")
C = TypeVar("C", bound="ConfigClass")

#: Marks a required field (``uid: str = MISSING``); ``validate()`` lists the ones still
#: unset. It is ``dataclasses.MISSING``, typed ``Any`` so that it fits every annotation.
MISSING: Any = dataclasses.MISSING


class ConfigClass(Protocol):
    """What every ``@configclass`` class provides: a structural type for generic code.

    Annotate a parameter ``type[ConfigClass]`` (or an instance ``ConfigClass``) where any
    config class is accepted; the decorated classes match it without inheriting from it.
    """

    __dataclass_fields__: ClassVar[dict[str, Any]]

    def to_dict(self) -> dict[str, Any]:
        """Plain data: nested configs become dicts, callables ``"module:name"``."""
        ...

    @classmethod
    def from_dict(cls: type[C], data: Any, path: str = "") -> C:
        """An instance built from a mapping; ``ConfigError`` names the bad entry's path."""
        ...

    @classmethod
    def _resolve_subclass(cls, data: dict, path: str) -> type: ...

    @classmethod
    def _build_from_dict(cls: type[C], data: dict, path: str) -> C: ...

    def replace(self: C, **changes: Any) -> C:
        """A deep copy with ``changes`` applied."""
        ...

    def copy(self: C) -> C:
        """A deep copy."""
        ...

    def validate(self, prefix: str = "") -> list[str]:
        """The still-``MISSING`` fields; without ``prefix`` any of them raises ``ConfigError``."""
        ...


def _missing() -> Any:
    return MISSING


def _is_data_member(name: str, value: Any) -> bool:
    if name.startswith("__") or inspect.isclass(value) or inspect.isroutine(value):
        return False
    if isinstance(value, (property, classmethod, staticmethod, dataclasses.Field)):
        return False
    return True


def _inherited_types(cls: type) -> dict[str, Any]:
    """Field name -> declared type of the fields the bases define."""
    import typing

    types: dict[str, Any] = {}
    for base in reversed(cls.__mro__[1:]):
        fields = getattr(base, "__dataclass_fields__", {})
        if not fields:
            continue
        try:  # resolve string annotations in the base's own module
            hints = typing.get_type_hints(base)
        except Exception:
            hints = {}
        for name, f in fields.items():
            types[name] = hints.get(name, f.type)
    return types


def _annotate(cls: type) -> None:
    """Give unannotated data members an annotation so they become fields."""
    ann = dict(cls.__dict__.get("__annotations__", {}))
    inherited = _inherited_types(cls)
    for name, value in list(cls.__dict__.items()):
        if name in ann or not _is_data_member(name, value):
            continue
        if name.startswith("_") and name not in inherited:
            continue
        if name in inherited:  # a redefined field keeps the type its base declared
            ann[name] = inherited[name]
        else:
            ann[name] = type(value) if value is not MISSING else Any
    cls.__annotations__ = ann


def _wrap_defaults(cls: type) -> None:
    """Turn mutable defaults into deep-copying factories."""
    for name in cls.__dict__.get("__annotations__", {}):
        if name not in cls.__dict__:
            # an annotated field without default: required
            setattr(cls, name, dataclasses.field(default_factory=_missing))
            continue
        value = cls.__dict__[name]
        if isinstance(value, dataclasses.Field):
            continue
        if value is MISSING:
            setattr(cls, name, dataclasses.field(default_factory=_missing))
        elif isinstance(value, (int, float, str, bool, type(None), tuple, frozenset)) and _immutable(value):
            continue
        else:
            setattr(cls, name, dataclasses.field(default_factory=_copier(value)))


def _immutable(value: Any) -> bool:
    if isinstance(value, (tuple, frozenset)):
        return all(_immutable(v) for v in value)
    return isinstance(value, (int, float, str, bool, type(None)))


def _copier(value: Any) -> Callable[[], Any]:
    def factory() -> Any:
        return copy.deepcopy(value)

    return factory


@dataclass_transform(field_specifiers=(dataclasses.field, dataclasses.Field))
def configclass(cls: type[T] | None = None, **kwargs: Any) -> Any:
    """Class decorator making ``cls`` a config dataclass (see module docstring).

    Type checkers read the fields through :pep:`681` (``dataclass_transform``). The
    methods added here (``from_dict``, ``to_dict``, ``replace``, ``copy``,
    ``validate``) are declared to mypy by the plugin
    ``embodichain_core/utils/mypy_plugin.py`` (see docs/architecture.md).
    """

    def wrap(klass: type[T]) -> type[T]:
        _annotate(klass)
        _wrap_defaults(klass)
        klass = dataclasses.dataclass(klass, **kwargs)
        for name, func in _METHODS.items():
            if name not in klass.__dict__ and not _defined_in_user_base(klass, name):
                setattr(klass, name, func)
        setattr(klass, "__configclass__", True)  # a runtime marker (is_configclass), not a declared field
        return klass

    if cls is None:
        return wrap
    return wrap(cls)


def _defined_in_user_base(klass: type, name: str) -> bool:
    for base in klass.__mro__[1:]:
        if name in base.__dict__ and base.__dict__[name] is not _METHODS.get(name):
            if base is object:
                return False
            return True
    return False


def is_configclass(obj: Any) -> bool:
    """True for config classes and their instances."""
    return getattr(obj, "__configclass__", False) is True


# --- methods attached to every config class -------------------------------------------


def _to_dict(self: Any) -> dict[str, Any]:
    """Convert to plain data: nested configs become dicts, callables ``"module:name"``."""
    return {f.name: to_plain(getattr(self, f.name)) for f in dataclasses.fields(self)}


def _from_dict(cls: type[C], data: Any, path: str = "") -> C:
    """Build an instance from a mapping; unknown keys and bad types raise ``ConfigError``."""
    if is_configclass(data) and isinstance(data, cls):
        return data
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a mapping for {cls.__name__}, got {type(data).__name__}")
    resolved: type[C] = cls._resolve_subclass(data, path)
    return resolved._build_from_dict(data, path)


def _resolve_subclass(cls: type[C], data: dict, path: str) -> type[C]:
    """Hook: pick a subclass from a discriminator key. Default: ``cls`` itself."""
    return cls


def _build_from_dict(cls: type[C], data: dict, path: str) -> C:
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    hints = _type_hints(cls)
    kwargs: dict[str, Any] = {}
    aliases = getattr(cls, "_key_aliases", {})
    for key, value in data.items():
        name = aliases.get(key, key)
        if name not in fields:
            raise unknown_key(path, str(key), fields.keys(), what=f"{cls.__name__} key")
        kwargs[name] = convert_value(value, hints.get(name, Any), join_path(path, key))
    try:
        return cls(**kwargs)
    except ConfigError as err:
        raise err if err.path else err.under(path) if path else err
    except (TypeError, ValueError) as err:
        raise ConfigError(path, f"cannot build {cls.__name__}: {err}") from err


def _type_hints(cls: type) -> dict[str, Any]:
    import typing

    try:
        return typing.get_type_hints(cls)
    except Exception:  # forward references that cannot be resolved: be lenient
        hints: dict[str, Any] = {}
        for klass in reversed(cls.__mro__):
            hints.update(getattr(klass, "__annotations__", {}))
        return {k: (Any if isinstance(v, str) else v) for k, v in hints.items()}


def _replace(self: C, **changes: Any) -> C:
    """A copy with ``changes`` applied (``dataclasses.replace``)."""
    return dataclasses.replace(copy.deepcopy(self), **changes)


def _copy(self: T) -> T:
    """A deep copy."""
    return copy.deepcopy(self)


def _validate(self: Any, prefix: str = "") -> list[str]:
    """Raise ``ConfigError`` listing every field that is still ``MISSING``."""
    missing = _find_missing(self, prefix)
    if missing and not prefix:
        raise ConfigError("", "missing required config values: " + ", ".join(missing))
    return missing


def _find_missing(obj: Any, prefix: str) -> list[str]:
    out: list[str] = []
    if is_configclass(obj) and not inspect.isclass(obj):
        for f in dataclasses.fields(obj):
            out += _find_missing(getattr(obj, f.name), join_path(prefix, f.name))
    elif isinstance(obj, dict):
        for k, v in obj.items():
            out += _find_missing(v, join_path(prefix, str(k)))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            out += _find_missing(v, f"{prefix}[{i}]")
    elif obj is MISSING or isinstance(obj, type(MISSING)):
        out.append(prefix)
    return out


_METHODS: dict[str, Any] = {
    "to_dict": _to_dict,
    "from_dict": classmethod(_from_dict),
    "_resolve_subclass": classmethod(_resolve_subclass),
    "_build_from_dict": classmethod(_build_from_dict),
    "replace": _replace,
    "copy": _copy,
    "validate": _validate,
}
