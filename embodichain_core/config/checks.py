"""Value checks shared by the config validators: numbers, vectors, ``[low, high]`` ranges.

Every check raises :class:`~embodichain_core.config.errors.ConfigError` with the
config path of the value and says what was expected, so a bad value is reported
at build time instead of deep inside MuJoCo or a functor.

Example:
    >>> check_number(0.5, "rigid_object[0].attrs.restitution", low=0.0, high=1.0)
    0.5
    >>> check_vector([0, 0, 1], 3, "robot.init_pos")
    [0.0, 0.0, 1.0]
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from embodichain_core.config.errors import ConfigError

__all__ = ["is_number", "check_number", "check_int", "check_vector", "check_range", "describe"]


def is_number(value: Any) -> bool:
    """True for ints and floats (numpy scalars included), never for ``bool``."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def describe(value: Any) -> str:
    """``"str 'heavy'"``: the type and a short repr of a value, for messages."""
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 60 else text[:57] + '...'}"


def _num(value: float) -> str:
    """A bound for messages: ints without exponent (``1000000``), floats with ``:g``."""
    return str(int(value)) if float(value).is_integer() and abs(value) < 1e15 else f"{value:g}"


def _bounds_text(low: Optional[float], high: Optional[float], low_open: bool) -> str:
    if low is not None and high is not None:
        return f"in {'(' if low_open else '['}{_num(low)}, {_num(high)}]"
    if low is not None:
        return f"{'>' if low_open else '>='} {_num(low)}"
    return f"<= {_num(high)}" if high is not None else ""


def check_number(
    value: Any,
    path: str,
    *,
    low: Optional[float] = None,
    high: Optional[float] = None,
    low_open: bool = False,
    what: str = "",
) -> float:
    """A finite number within the bounds; returns it as ``float``.

    Args:
        value: the value to check.
        path: its config path (for the error).
        low, high: inclusive bounds (``None``: unbounded).
        low_open: ``low`` itself is excluded (``> low``).
        what: a short meaning appended to the message (``"kg"``).
    """
    rule = _bounds_text(low, high, low_open)
    unit = f" ({what})" if what else ""
    if not is_number(value) or not math.isfinite(float(value)):
        raise ConfigError(path, f"expected a finite number{' ' + rule if rule else ''}{unit}, got {describe(value)}")
    number = float(value)
    if (low is not None and (number < low or (low_open and number == low))) or (high is not None and number > high):
        raise ConfigError(path, f"must be {rule}{unit}, got {value!r}")
    return number


def check_int(value: Any, path: str, *, low: int = 1, high: Optional[int] = None, hint: str = "") -> int:
    """An int in ``[low, high]``; ``hint`` is appended to an out-of-range message."""
    if not (is_number(value) and math.isfinite(float(value)) and float(value).is_integer()) or isinstance(value, float):
        raise ConfigError(path, f"expected an int {_bounds_text(low, high, False)}, got {describe(value)}")
    number = int(value)
    if number < low or (high is not None and number > high):
        raise ConfigError(path, f"must be an int {_bounds_text(low, high, False)}, got {number}{hint}")
    return number


def check_vector(
    value: Any,
    n: int,
    path: str,
    *,
    low: Optional[float] = None,
    high: Optional[float] = None,
    low_open: bool = False,
    what: str = "",
) -> list[float]:
    """``n`` finite numbers within the bounds (a list or tuple); returns them as floats."""
    rule = "" if low is None and high is None else f", each {_bounds_text(low, high, low_open)}"
    unit = f" ({what})" if what else ""
    if isinstance(value, (str, bytes, dict)) or not isinstance(value, (list, tuple, np.ndarray)) or len(value) != n:
        raise ConfigError(path, f"expected {n} finite numbers{rule}{unit}, got {describe(value)}")
    return [
        check_number(v, f"{path}[{i}]", low=low, high=high, low_open=low_open, what=what) for i, v in enumerate(value)
    ]


def _bound(value: Any, path: str, width: Optional[int]) -> np.ndarray:
    """One bound of a range: a number or a flat list of ``width`` numbers."""
    if is_number(value):
        return np.asarray(float(value))
    if isinstance(value, (list, tuple)) and value and all(is_number(v) for v in value):
        if width is not None and len(value) not in (1, width):
            raise ConfigError(path, f"expected 1 or {width} values, got {len(value)}: {value!r}")
        return np.asarray([float(v) for v in value])
    raise ConfigError(path, f"expected a number or a list of numbers, got {describe(value)}")


def check_range(
    value: Any,
    path: str,
    *,
    width: Optional[int] = None,
    low: Optional[float] = None,
    high: Optional[float] = None,
    low_open: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """A ``[low, high]`` pair: finite, same length (or a scalar bound), ``low <= high``,
    and every value within ``[low, high]`` of the allowed bounds when given.

    Returns:
        The two bounds as float arrays.
    """
    if isinstance(value, (str, bytes, dict)) or not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ConfigError(path, f"expected a [low, high] pair, got {describe(value)}")
    lo, hi = _bound(value[0], f"{path}[0]", width), _bound(value[1], f"{path}[1]", width)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise ConfigError(path, f"bounds must be finite, got {value!r}")
    if lo.ndim and hi.ndim and lo.shape != hi.shape:
        raise ConfigError(path, f"low and high have different lengths in {value!r}")
    if (lo > hi).any():
        raise ConfigError(path, f"low {value[0]!r} is above high {value[1]!r} (write [low, high])")
    rule = _bounds_text(low, high, low_open)
    for bound in (lo, hi):
        below = low is not None and ((bound < low).any() or (low_open and (bound == low).any()))
        if below or (high is not None and (bound > high).any()):
            raise ConfigError(path, f"every bound must be {rule}, got {value!r}")
    return lo, hi
