"""Env attributes that functors pass between each other, checked at build.

Some functors talk through an env attribute: ``randomize_target_pose`` stores the goals in
``env.<store_key>``; ``target_position`` and the distance rewards read ``env.<target_pose_key>``.
A functor declares which of its params names such an attribute:

* ``writes_env_key = "store_key"`` on a writer (an event functor);
* ``reads_env_key = "target_pose_key"`` on a reader (an observation or a reward).

When the env is built, :func:`check_env_keys` matches each reader's key against the env's
attributes and the writers' keys. A reader whose key no writer stores, while some writer
stores another key, is a :class:`~embodichain_core.config.errors.ConfigError` naming both
functors and both keys. Without any writer the key may still come from task code, so it is
checked once more at the end of the first reset (:func:`check_after_first_reset`).
"""

from __future__ import annotations

import inspect
from typing import Any, NamedTuple

from embodichain_core.config.errors import ConfigError, join_path

__all__ = ["READS_ATTR", "WRITES_ATTR", "KeyUse", "check_env_keys", "check_after_first_reset"]

READS_ATTR = "reads_env_key"
WRITES_ATTR = "writes_env_key"


class KeyUse(NamedTuple):
    """One functor's use of an env attribute."""

    path: str  # the functor's config path (``env.observations.goal``)
    functor: str
    param: str  # the param naming the attribute (``target_pose_key``)
    key: str  # the attribute (``goal_pose``)


def _functor_name(func: Any) -> str:
    return getattr(func, "__name__", type(func).__name__)


def _declared_key(entry: Any, attr: str) -> KeyUse | None:
    """The entry's use of an env attribute, when its functor declares one."""
    func = entry.func
    param = getattr(func, attr, None) or getattr(type(func), attr, None)
    if not isinstance(param, str):
        return None
    key = entry.cfg.params.get(param)
    if key is None:
        target = func.__call__ if entry.is_class else func
        default = inspect.signature(target).parameters.get(param)
        key = None if default is None or default.default is inspect.Parameter.empty else default.default
    if not isinstance(key, str):
        return None
    return KeyUse(entry.path, _functor_name(func), param, key)


def _uses(manager: Any, attr: str) -> list[KeyUse]:
    if manager is None:
        return []
    return [use for entry in manager.entries.values() if (use := _declared_key(entry, attr)) is not None]


def check_env_keys(env: Any) -> list[KeyUse]:
    """Check the readers of env attributes against the writers (at build).

    Returns:
        The readers whose attribute neither exists nor is stored by a writer (left to
        task code; checked again by :func:`check_after_first_reset`).

    Raises:
        ConfigError: at ``<reader>.params.<param>``: writers exist, none stores the key.
    """
    writers = _uses(env.event_manager, WRITES_ATTR)
    stored = {w.key for w in writers}
    pending = []
    for reader in _uses(env.observation_manager, READS_ATTR) + _uses(env.reward_manager, READS_ATTR):
        if reader.key in stored or getattr(env, reader.key, None) is not None:
            continue
        if not writers:
            pending.append(reader)
            continue
        others = "; ".join(f"{w.functor} ({w.path}) stores env.{w.key} (params.{w.param})" for w in writers)
        raise ConfigError(
            join_path(reader.path, "params", reader.param),
            f"{reader.functor} reads env.{reader.key}, which no functor stores: {others}. "
            f"Use one key for both (set params.{reader.param} here or the writer's params to the same name)",
        )
    return pending


def check_after_first_reset(env: Any, pending: list[KeyUse]) -> None:
    """Raise for a reader whose attribute still does not exist after the first reset.

    Raises:
        ConfigError: at ``<reader>.params.<param>``, naming the reader and the key.
    """
    for reader in pending:
        if getattr(env, reader.key, None) is None:
            raise ConfigError(
                join_path(reader.path, "params", reader.param),
                f"{reader.functor} reads env.{reader.key}, which does not exist after the first reset: no event "
                f"stores it (e.g. randomize_target_pose with store_key: {reader.key!r}) and the task does not set it",
            )
