"""Helpers shared by the functors: env ids, per-env sampling, parameter errors.

Every random draw goes through :func:`uniform` (or :func:`randint`), one row per env
in ``env_ids``, each row from that env's episode stream ``env.rng`` (see
:mod:`embodichain_core.envs.episode_rng`): an env's episode is a function of the seed,
its env index and its episode index alone, whatever the other envs do.
"""

from __future__ import annotations

import functools
import inspect
import math
from typing import Any, Callable, Optional, Sequence

import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.entities.base import env_index

_MANAGERS = ("event_manager", "observation_manager", "reward_manager", "action_manager", "dataset_manager")


class ParamError(ConfigError):
    """A functor parameter is wrong; the path is ``<functor>.params.<param>`` until located."""

    def __init__(self, functor: str, param: str, reason: str):
        self.functor, self.param = functor, param
        super().__init__(f"{functor}.params.{param}", f"functor {functor!r}: {reason}")

    def located(self, env: Any, params: dict) -> ConfigError:
        """The same error with the path of the config entry holding ``params``."""
        where = config_path(env, self.functor, params)
        if where is None:
            return self
        err = ConfigError(f"{where}.params.{self.param}", self.reason)
        err.__cause__ = self
        return err


def config_path(env: Any, functor: str, params: dict) -> Optional[str]:
    """Path (``env.events.<name>``) of the manager entry calling ``functor`` with ``params``."""
    for attr in _MANAGERS:
        manager = getattr(env, attr, None)
        for entry in getattr(manager, "entries", {}).values():
            func = entry.cfg.func
            if getattr(func, "__name__", None) != functor:
                continue
            if all(entry.cfg.params.get(k) is v for k, v in params.items()):
                return entry.path
    return None


def validated(check: Callable[..., None], lead: int = 1) -> Callable[[Callable], Callable]:
    """Decorate a function functor so ``check(env, **params)`` runs on its first call.

    ``check`` raises :class:`ParamError`; the error is re-raised with the path of the
    config entry (``env.events.<name>.params.<param>``). Checks run once per
    functor and set of param objects, so the hot path stays cheap. The wrapped
    function keeps its signature (the managers check params against it).

    Args:
        check: the validator.
        lead: positional arguments after ``env`` that are not params (``env_ids`` or
            ``obs``: 1; rewards' ``obs, action, info``: 3); further positional
            arguments are passed to ``check`` by name.
    """

    def decorate(fn: Callable) -> Callable:
        names = list(inspect.signature(fn).parameters)[1 + lead :]

        @functools.wraps(fn)
        def wrapper(env: Any, *args: Any, **params: Any) -> Any:
            if len(args) > lead:
                params.update(zip(names, args[lead:]))
                args = args[:lead]
            seen = env.__dict__.setdefault("_embodichain_functors_checked", set())
            key = (fn.__qualname__, tuple((k, id(v)) for k, v in params.items()))
            if key not in seen:
                try:
                    check(env, **params)
                except ParamError as err:
                    raise err.located(env, params) from None
                seen.add(key)
            return fn(env, *args, **params)

        wrapper.check_params = check  # type: ignore[attr-defined]
        return wrapper

    return decorate


def env_ids_of(env: Any, env_ids: Any) -> torch.Tensor:
    """``env_ids`` as a long tensor; ``None`` (startup events) means every env."""
    if env_ids is None:
        return torch.arange(env.num_envs)
    return env_index(env_ids, env.num_envs)


def uniform(env: Any, env_ids: Any, low: Any, high: Any, per_env: Sequence[int] = ()) -> torch.Tensor:
    """Per-env draws in ``[low, high)`` (float64), shape ``(n, *per_env) + broadcast(low, high)``.

    Row ``i`` comes from the episode stream of env ``env_ids[i]`` (``None``: every env).
    """
    return torch.from_numpy(uniform_np(env, env_ids, low, high, per_env))


def uniform_np(env: Any, env_ids: Any, low: Any, high: Any, per_env: Sequence[int] = ()) -> np.ndarray:
    """:func:`uniform` as a numpy array (the same draws)."""
    low_np, span = _bounds(low, high)
    draw = env.rng.random(env_ids, tuple(per_env) + low_np.shape)
    draw *= span
    draw += low_np
    return draw


_SPANS: dict[tuple[int, int], tuple[Any, Any, np.ndarray, np.ndarray]] = {}


def _bounds(low: Any, high: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high - low)`` broadcast to one shape, as float64 numpy; cached for tensors
    (the ranges of :func:`as_range` are converted once per param)."""
    key = (id(low), id(high))
    hit = _SPANS.get(key)
    if hit is not None and hit[0] is low and hit[1] is high:
        return hit[2], hit[3]
    lo = np.asarray(low.numpy() if isinstance(low, torch.Tensor) else low, dtype=np.float64)
    hi = np.asarray(high.numpy() if isinstance(high, torch.Tensor) else high, dtype=np.float64)
    lo, hi = np.broadcast_arrays(lo, hi)
    lo, span = np.array(lo), np.array(hi - lo)  # own contiguous copies, 0-d kept 0-d
    if isinstance(low, torch.Tensor) and isinstance(high, torch.Tensor):
        if len(_SPANS) >= _RANGE_CACHE_SIZE:
            _SPANS.clear()
        _SPANS[key] = (low, high, lo, span)
    return lo, span


def randint(env: Any, env_ids: Any, high: int, per_env: Sequence[int] = ()) -> torch.Tensor:
    """Integers in ``[0, high)``, shape ``(n, *per_env)``, one row per env's stream (int64)."""
    return torch.from_numpy(env.rng.integers(env_ids, int(high), tuple(per_env)))


_RANGES: dict[tuple[int, Optional[int]], tuple[Any, torch.Tensor, torch.Tensor]] = {}
_RANGE_CACHE_SIZE = 4096


def as_range(value: Any, functor: str, param: str, width: Optional[int] = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Check a ``[low, high]`` param and return ``(low, high)`` float64 tensors.

    Each bound is a number or a list; with ``width`` a number broadcasts to
    ``width`` values and a list must have ``width`` values. Results are cached per
    param object (configs keep their params), so hot paths convert them once.

    Raises:
        ParamError: malformed, non-finite, wrong width, or low above high.
    """
    cached = _RANGES.get((id(value), width))
    if cached is not None and cached[0] is value:
        return cached[1], cached[2]
    low, high = _parse_range(value, functor, param, width)
    if isinstance(value, (list, tuple)):
        if len(_RANGES) >= _RANGE_CACHE_SIZE:  # bounded: configs hold few ranges, tests build many
            _RANGES.clear()
        _RANGES[(id(value), width)] = (value, low, high)
    return low, high


def _parse_range(value: Any, functor: str, param: str, width: Optional[int]) -> tuple[torch.Tensor, torch.Tensor]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ParamError(functor, param, f"expected [low, high], got {value!r}")
    try:
        low, high = (torch.as_tensor(v, dtype=torch.float64) for v in value)
    except (TypeError, ValueError, RuntimeError):
        raise ParamError(functor, param, f"bounds must be numbers or lists of numbers, got {value!r}") from None
    if width is not None:
        for bound in (low, high):
            if bound.dim() > 1 or (bound.dim() == 1 and bound.numel() not in (1, width)):
                raise ParamError(functor, param, f"each bound needs 1 or {width} values, got {value!r}")
        low, high = low.reshape(-1).expand(width).clone(), high.reshape(-1).expand(width).clone()
    elif low.shape != high.shape:
        raise ParamError(functor, param, f"low and high have different shapes in {value!r}")
    if not (torch.isfinite(low).all() and torch.isfinite(high).all()):
        raise ParamError(functor, param, f"bounds must be finite, got {value!r}")
    if (low > high).any():
        raise ParamError(functor, param, f"low {value[0]!r} is above high {value[1]!r}")
    return low, high


def check_optional_range(value: Any, functor: str, param: str, width: Optional[int] = None) -> None:
    """:func:`as_range` for a param that may be ``None``."""
    if value is not None:
        as_range(value, functor, param, width)


def check_probability(value: Any, functor: str, param: str) -> None:
    """A number in [0, 1]."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= float(value) <= 1.0:
        raise ParamError(functor, param, f"must be a probability in [0, 1], got {value!r}")


def check_positive(value: Any, functor: str, param: str, allow_zero: bool = False) -> None:
    """A finite number > 0 (or >= 0)."""
    ok = not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        raise ParamError(functor, param, f"must be a number {'>=' if allow_zero else '>'} 0, got {value!r}")


def entity_of(env: Any, entity_cfg: Any, functor: str, kinds: Sequence[type], param: str = "entity_cfg") -> Any:
    """The scene entity named by ``entity_cfg`` if it is one of ``kinds``."""
    uid = entity_cfg.get("uid") if isinstance(entity_cfg, dict) else getattr(entity_cfg, "uid", None)
    if uid is None:
        raise ParamError(functor, param, f"expected a SceneEntityCfg, got {entity_cfg!r}")
    entity = env.scene.get(uid)
    if entity is None:
        raise ParamError(functor, param, f"no entity {uid!r} in the scene")
    if not isinstance(entity, tuple(kinds)):
        names = " or ".join(k.__name__ for k in kinds)
        raise ParamError(functor, param, f"{uid!r} is a {type(entity).__name__}; expected a {names}")
    return entity
