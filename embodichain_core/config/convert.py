"""Type-directed conversion of plain data (JSON/YAML) into typed config values."""

from __future__ import annotations

import collections.abc as cabc
import enum
import inspect
import types
import typing
from dataclasses import MISSING
from typing import TYPE_CHECKING, Any, Literal, TypeGuard, Union

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.utils.suggest import did_you_mean

if TYPE_CHECKING:  # configclass imports this module
    from embodichain_core.utils.configclass import ConfigClass

_NONE = type(None)


def convert_value(value: Any, hint: Any, path: str) -> Any:
    """Convert ``value`` to match the type ``hint``; raise ``ConfigError`` otherwise.

    Nested config classes are built with their ``from_dict``; lists, tuples and
    dicts are converted element-wise; ``int`` is accepted where ``float`` is
    expected; a ``bool`` is never accepted as a number.
    """
    if value is MISSING or hint is Any or hint is object:
        return value
    origin = typing.get_origin(hint)
    if origin is Union or (types.UnionType is not None and isinstance(hint, types.UnionType)):
        return _convert_union(value, typing.get_args(hint), path)
    if origin is Literal:
        choices = typing.get_args(hint)
        if value not in choices:
            raise ConfigError(path, f"invalid value {value!r}.{did_you_mean(str(value), map(str, choices))}")
        return value
    if origin in (list, cabc.Sequence, cabc.MutableSequence, set, frozenset):
        return _convert_list(value, hint, path)
    if origin is tuple:
        return _convert_tuple(value, typing.get_args(hint), path)
    if origin in (dict, cabc.Mapping, cabc.MutableMapping):
        return _convert_dict(value, typing.get_args(hint), path)
    if origin is type or origin in (cabc.Callable,):
        return value
    if inspect.isclass(hint):
        return _convert_class(value, hint, path)
    return value


def _convert_union(value: Any, members: tuple, path: str) -> Any:
    if value is None and _NONE in members:
        return None
    errors: list[ConfigError] = []
    # try config classes and containers first when value is structured
    for member in members:
        if member is _NONE:
            continue
        try:
            return convert_value(value, member, path)
        except ConfigError as err:
            errors.append(err)
    if len(errors) == 1:
        raise errors[0]
    deepest = max(errors, key=lambda err: len(err.path))
    if len(deepest.path) > len(path):  # a member matched the structure; an item inside it is wrong
        raise deepest
    names = ", ".join(_type_name(m) for m in members if m is not _NONE)
    raise ConfigError(path, f"value {value!r} does not match any of: {names}")


def _type_name(hint: Any) -> str:
    """``int``, or a Literal's values (``'auto'``) for an error message."""
    if typing.get_origin(hint) is Literal:
        return " or ".join(repr(v) for v in typing.get_args(hint))
    return getattr(hint, "__name__", str(hint))


def _convert_list(value: Any, hint: Any, path: str) -> Any:
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple, set, frozenset)):
        raise ConfigError(path, f"expected a list, got {type(value).__name__} {value!r}")
    args = typing.get_args(hint)
    item = args[0] if args else Any
    return [convert_value(v, item, f"{path}[{i}]") for i, v in enumerate(value)]


def _convert_tuple(value: Any, args: tuple, path: str) -> Any:
    if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
        raise ConfigError(path, f"expected a sequence, got {type(value).__name__} {value!r}")
    if not args or (len(args) == 2 and args[1] is Ellipsis):
        item = args[0] if args else Any
        return tuple(convert_value(v, item, f"{path}[{i}]") for i, v in enumerate(value))
    if len(args) != len(value):
        raise ConfigError(path, f"expected {len(args)} values, got {len(value)}: {value!r}")
    return tuple(convert_value(v, a, f"{path}[{i}]") for i, (v, a) in enumerate(zip(value, args)))


def _convert_dict(value: Any, args: tuple, path: str) -> Any:
    if not isinstance(value, dict):
        raise ConfigError(path, f"expected a mapping, got {type(value).__name__} {value!r}")
    item = args[1] if len(args) == 2 else Any
    return {k: convert_value(v, item, join_path(path, str(k))) for k, v in value.items()}


def _is_config_type(hint: type) -> TypeGuard[type[ConfigClass]]:
    return bool(getattr(hint, "__configclass__", False))


def _convert_class(value: Any, hint: type, path: str) -> Any:
    if _is_config_type(hint):
        if isinstance(value, hint):
            return value
        try:
            return hint.from_dict(value, path)
        except ConfigError as err:
            # a check inside the class (``__post_init__``) names its field only: add the path
            if path and not _within(err.path, path):
                raise err.under(path) from None
            raise
    if issubclass(hint, enum.Enum):
        return _convert_enum(value, hint, path)
    if hint is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(path, f"expected true/false, got {type(value).__name__} {value!r}")
    if hint in (int, float):
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if hint is int and isinstance(value, float):
            ok = value.is_integer()
            value = int(value) if ok else value
        if not ok:
            raise ConfigError(path, f"expected {hint.__name__}, got {type(value).__name__} {value!r}")
        return value
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected a string, got {type(value).__name__} {value!r}")
        return value
    if hint in (list, tuple):
        if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
            raise ConfigError(path, f"expected a list of values, got {type(value).__name__} {value!r}")
        return hint(value)
    return value


def _within(path: str, prefix: str) -> bool:
    """``path`` is ``prefix`` or lies below it."""
    return path == prefix or path.startswith((f"{prefix}.", f"{prefix}["))


def _convert_enum(value: Any, hint: type[enum.Enum], path: str) -> Any:
    if isinstance(value, hint):
        return value
    for member in hint:
        if str(value).lower() in (member.name.lower(), str(member.value).lower()):
            return member
    names = [m.name for m in hint]
    raise ConfigError(path, f"invalid value {value!r}.{did_you_mean(str(value), names)}")


def to_plain(value: Any) -> Any:
    """Convert a config value to JSON-friendly plain data."""
    if getattr(value, "__configclass__", False) and not inspect.isclass(value):
        return value.to_dict()
    if isinstance(value, dict):
        return {k: to_plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_plain(v) for v in value]
    if isinstance(value, enum.Enum):
        return value.value
    if inspect.isclass(value) or inspect.isroutine(value):
        module = getattr(value, "__module__", None)
        return f"{module}:{value.__qualname__}" if module else value.__qualname__
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        return value.tolist()
    if isinstance(value, slice):
        return None if value == slice(None) else [value.start, value.stop, value.step]
    return value
