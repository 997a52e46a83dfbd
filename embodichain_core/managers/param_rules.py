"""Functor params checked by naming convention, for every functor of every plugin.

A functor's own ``check_params`` hook knows its params best; these rules catch what
any functor would get wrong with the same names, so plugins need not repeat them:

=====================================================  ==========================================
param name                                             rule
=====================================================  ==========================================
``*_range``                                            ``[low, high]``: finite numbers or lists of
                                                       numbers of one length, ``low <= high``; a
                                                       mapping of such pairs (per link); ``None``
                                                       means "not randomized"
``*color*_range``, ``metallic_range``,                 every bound in ``[0, 1]`` (colour bounds: 1, 3
                                                       or 4 values)
``roughness_range``, ``*_prob_range``
``mass_range``                                         bounds > 0 (unless ``relative`` is true)
``friction_range``, ``damping_range``,                 bounds >= 0 (unless ``relative`` is true)
``stiffness_range``, ``max_effort_range``
``*scale*_range``                                      bounds > 0 (scale factors)
``*_range`` (any)                                      every bound of magnitude <= 1e6
``*_prob``, ``prob``, ``probability``                  a number in ``[0, 1]``
any number, anywhere in the params                     not NaN
a param annotated ``bool``/``int``/``float``/``str``   that type (``Optional``: or ``None``)
a param annotated :data:`DataPath` (``Optional``,      an asset name or path ``get_data_path`` finds
or a list of them)
=====================================================  ==========================================

The signature rules (:func:`check_signature`, :func:`check_param_types`,
:func:`check_data_paths`) read the functor's signature after its ``min_argc`` positional
arguments; the params naming scene entities are found there too (:mod:`.entity_params`).

Example:
    >>> check_named_params({"mass_range": [2.0, 1.0]}, "env.events.m", "randomize_rigid_object_mass")
    Traceback (most recent call last):
    ...
    embodichain_core.config.errors.ConfigError: env.events.m.params.mass_range: ...
"""

from __future__ import annotations

import inspect
import math
import re
from typing import Any, NewType, Optional

import numpy as np

from embodichain_core.config.checks import check_number, check_range, describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.utils.suggest import did_you_mean

__all__ = [
    "check_named_params",
    "check_param_types",
    "check_signature",
    "check_data_path",
    "check_data_paths",
    "data_path_params",
    "annotated_as",
    "param_items",
    "functor_params",
    "range_bounds",
    "DataPath",
    "MAX_RANGE_MAGNITUDE",
]

#: Largest magnitude of a ``*_range`` bound (metres, degrees, kg, intensities alike).
MAX_RANGE_MAGNITUDE = 1.0e6
_UNIT = (0.0, 1.0, False)
_POSITIVE = (0.0, None, True)
_NON_NEGATIVE = (0.0, None, False)
_RELATIVE_NAMES = {
    "mass_range": _POSITIVE,
    "friction_range": _NON_NEGATIVE,
    "damping_range": _NON_NEGATIVE,
    "stiffness_range": _NON_NEGATIVE,
    "max_effort_range": _NON_NEGATIVE,
}


def range_bounds(key: str, params: dict) -> tuple[Optional[float], Optional[float], bool]:
    """``(low, high, low_open)`` allowed for the bounds of the range param ``key``."""
    if "color" in key or key in ("metallic_range", "roughness_range") or key.endswith("_prob_range"):
        return _UNIT
    if key in _RELATIVE_NAMES:
        return (None, None, False) if params.get("relative") is True else _RELATIVE_NAMES[key]
    if "scale" in key:
        return _POSITIVE
    return None, None, False


def _is_range_key(key: str) -> bool:
    return key.endswith("_range")


def _is_prob_key(key: str) -> bool:
    return key in ("prob", "probability") or key.endswith("_prob")


def check_named_params(params: Any, path: str, name: str) -> None:
    """Check ``params`` (of the functor ``name`` at config ``path``) by naming convention.

    Raises:
        ConfigError: at ``<path>.params.<key>``, naming the functor and the rule.
    """
    if not isinstance(params, dict):
        raise ConfigError(join_path(path, "params"), f"expected a mapping of params, got {type(params).__name__}")
    for key, value in params.items():
        where = join_path(path, "params", str(key))
        try:
            _check_nan(value, where)
            if value is None:
                continue
            if _is_range_key(str(key)):
                _check_range_param(str(key), value, params, where)
            elif _is_prob_key(str(key)):
                check_number(value, where, low=0.0, high=1.0, what="a probability")
        except ConfigError as err:
            raise ConfigError(err.path, f"functor {name!r}: {err.reason}") from None


def _check_range_param(key: str, value: Any, params: dict, where: str) -> None:
    low, high, low_open = range_bounds(key, params)
    if "color" in key and isinstance(value, (list, tuple)):
        for i, bound in enumerate(value):
            if isinstance(bound, (list, tuple)) and len(bound) not in (1, 3, 4):
                raise ConfigError(
                    f"{where}[{i}]", f"a colour bound has 1, 3 (RGB) or 4 (RGBA) values, got {len(bound)}: {bound!r}"
                )
    if isinstance(value, dict):
        if not value:
            raise ConfigError(where, "an empty mapping of ranges sets nothing; give [low, high]")
        for sub, pair in value.items():
            _check_magnitude(
                check_range(pair, join_path(where, str(sub)), low=low, high=high, low_open=low_open),
                pair,
                join_path(where, str(sub)),
            )
        return
    _check_magnitude(check_range(value, where, low=low, high=high, low_open=low_open), value, where)


def _check_magnitude(bounds: tuple, value: Any, where: str) -> None:
    """No range bound beyond :data:`MAX_RANGE_MAGNITUDE` (whatever its unit, a sign of a
    wrong exponent or a placeholder)."""
    if any(float(np.abs(b).max(initial=0.0)) > MAX_RANGE_MAGNITUDE for b in bounds):
        raise ConfigError(
            where, f"a bound of magnitude above {MAX_RANGE_MAGNITUDE:g} is not a plausible range, got {value!r}"
        )


def _check_nan(value: Any, where: str, depth: int = 0) -> None:
    """No NaN anywhere in (nested lists/dicts of) a param value."""
    if isinstance(value, float) and math.isnan(value):
        raise ConfigError(where, "NaN is not a valid value")
    if depth > 6:
        return
    if isinstance(value, (list, tuple)):
        for i, item in enumerate(value):
            _check_nan(item, f"{where}[{i}]", depth + 1)
    elif isinstance(value, dict):
        for key, item in value.items():
            _check_nan(item, join_path(where, str(key)), depth + 1)


#: Annotations checked by :func:`check_param_types` -> (accepted types, description).
_SIMPLE_TYPES: dict[str, tuple[tuple[type, ...], str]] = {
    "bool": ((bool,), "true/false"),
    "int": ((int,), "an int"),
    "float": ((int, float), "a number"),
    "str": ((str,), "a string"),
}


def _annotation_name(annotation: Any) -> tuple[str, bool]:
    """``("bool", optional)`` for ``bool``/``"bool"``/``Optional[bool]``; ``("", ...)`` otherwise."""
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", str(annotation))
    text = text.replace("typing.", "").strip()
    for wrapper in ("Optional[", "Union[None, "):
        if text.startswith(wrapper) and text.endswith("]"):
            return text[len(wrapper) : -1].strip(), True
    if text.endswith("| None") or text.startswith("None |"):
        return text.replace("| None", "").replace("None |", "").strip(), True
    return text, False


def functor_params(func: Any, min_argc: Optional[int]) -> Optional[list[inspect.Parameter]]:
    """The params of ``func`` after its ``min_argc`` positional arguments (a class: its
    ``__call__``); ``None`` when the signature cannot be read or ``min_argc`` is ``None``
    (the params go to a class's constructor)."""
    if min_argc is None:
        return None
    target = func.__call__ if inspect.isclass(func) else func
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return None
    return [p for p in sig.parameters.values() if p.name != "self"][min_argc:]


def _name(func: Any) -> str:
    return getattr(func, "__name__", repr(func))


def check_signature(func: Any, params: dict, min_argc: int, path: str) -> None:
    """Unknown params and missing required params are errors naming the functor."""
    args = functor_params(func, min_argc)
    if args is None:
        return
    named = [p for p in args if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    if not any(p.kind is p.VAR_KEYWORD for p in args):
        allowed = {p.name for p in named}
        for key in params:
            if key not in allowed:
                raise ConfigError(
                    join_path(path, "params", key),
                    f"functor {_name(func)!r} has no parameter {key!r}.{did_you_mean(key, allowed)}",
                )
    missing = [p.name for p in named if p.default is p.empty and p.name not in params]
    if missing:
        raise ConfigError(join_path(path, "params"), f"functor {_name(func)!r} needs parameter(s) {missing}")


def check_param_types(func: Any, params: dict, path: str, min_argc: int) -> None:
    """Params annotated ``bool``, ``int``, ``float`` or ``str`` (or ``Optional`` of one)
    in the functor's signature must have that type (``"yes"`` is not a bool)."""
    for param in functor_params(func, min_argc) or []:
        if param.name not in params or param.annotation is param.empty:
            continue
        kind, optional = _annotation_name(param.annotation)
        kind = "str" if kind.rsplit(".", 1)[-1] == "DataPath" else kind  # a DataPath is a str
        value = params[param.name]
        if kind not in _SIMPLE_TYPES or (value is None and optional):
            continue
        types, text = _SIMPLE_TYPES[kind]
        if not isinstance(value, types) or (isinstance(value, bool) and bool not in types):
            raise ConfigError(
                join_path(path, "params", param.name),
                f"functor {_name(func)!r}: expected {text}, got {type(value).__name__} {value!r}",
            )


#: The annotation of a functor param naming asset data: a ``get_data_path`` name or a path.
#: The manager checks that it exists when the config is validated (a glob pattern is left to
#: the functor) and passes the string as given; so does ``Optional[DataPath]`` (``None``: not
#: given) and a list of them (each item). An unannotated param is passed as given, unchecked.
DataPath = NewType("DataPath", str)

_DATA_PATH = re.compile(r"\bDataPath\b")
_SEQUENCE = re.compile(r"\b(Sequence|List|list|Tuple|tuple|Iterable)\[")


def annotated_as(param: inspect.Parameter, type_name: "re.Pattern[str]") -> Optional[bool]:
    """Whether ``param``'s annotation names ``type_name`` (bare or ``Optional``: ``False``; a
    ``Sequence``/``List``/... of it: ``True``), else ``None`` (not annotated so, or ``**kwargs``)."""
    annotation = param.annotation
    if annotation is param.empty or param.kind is param.VAR_KEYWORD:
        return None
    text = annotation if isinstance(annotation, str) else str(annotation)
    return bool(_SEQUENCE.search(text)) if type_name.search(text) else None


def param_items(value: Any, where: str, many: bool) -> list[tuple[str, Any]]:
    """``(path, item)`` of each item of a list or tuple given to a param taking a sequence,
    else ``[(where, value)]``."""
    if many and isinstance(value, (list, tuple)):
        return [(f"{where}[{i}]", item) for i, item in enumerate(value)]
    return [(where, value)]


def data_path_params(func: Any, min_argc: Optional[int]) -> dict[str, bool]:
    """The params of ``func`` annotated :data:`DataPath` -> whether each takes a list of them.

    Example:
        >>> def load(env, env_ids, textures: DataPath, meshes: list[DataPath], folder_path=None): ...
        >>> data_path_params(load, 2)
        {'textures': False, 'meshes': True}
    """
    found = {p.name: annotated_as(p, _DATA_PATH) for p in functor_params(func, min_argc) or []}
    return {name: many for name, many in found.items() if many is not None}


def check_data_paths(func: Any, params: dict, path: str, min_argc: Optional[int]) -> None:
    """Every param of ``params`` that ``func`` annotates :data:`DataPath` (see
    :func:`data_path_params`) names existing asset data (``None``: not given)."""
    label = _name(func)
    for key, many in data_path_params(func, min_argc).items():
        for where, item in param_items(params.get(key), join_path(path, "params", key), many):
            if item is not None:
                check_data_path(item, where, label)


def check_data_path(value: Any, path: str, functor: str = "") -> None:
    """An asset name or path that ``get_data_path`` resolves (a glob pattern is left to
    its functor)."""
    from embodichain_core.sim.data import get_data_path

    lead = f"functor {functor!r}: " if functor else ""
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(path, f"{lead}expected an asset name or path, got {describe(value)}")
    if any(char in value for char in "*?["):
        return
    try:
        get_data_path(value)
    except FileNotFoundError as err:
        raise ConfigError(path, lead + str(err).strip("\"'")) from None
