"""``register_env``: register a task class with gymnasium (``gym.make`` and ``gym.make_vec``).

The episode limit stays inside the env: ``max_episode_steps`` is never given to
gymnasium (its ``TimeLimit`` would collapse batched truncation); it becomes the
env's limit unless the config sets another. The spec is a
:class:`~embodichain_core.gym_vector.BatchedEnvSpec`: ``gym.make_vec`` gives ``(N,)``
rewards in every vectorization mode.

Example:
    >>> @register_env("MyTask-v0", max_episode_steps=200)
    ... class MyTask(EmbodiedEnv):
    ...     ...
    >>> env = gym.make("MyTask-v0", cfg=MyTaskCfg(num_envs=8))
"""

from __future__ import annotations

import functools
import json
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import gymnasium as gym

from embodichain_core.gym_vector import batched_spec, make_vec_env

REGISTERED_ENVS: dict[str, "EnvSpec"] = {}


@dataclass
class EnvSpec:
    """What ``register_env`` recorded for a task id."""

    uid: str
    cls: type
    max_episode_steps: Optional[int] = None
    default_kwargs: dict = field(default_factory=dict)

    def make(self, **kwargs: Any) -> Any:
        return self.cls(**{**self.default_kwargs, **kwargs})


def _entry(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _provided_by_plugins(uid: str, cls: type, kwargs: dict, max_episode_steps: Optional[int]) -> bool:
    """True when plugins manage ``uid`` in gymnasium: their spec stays (a warning when
    ``cls`` is none of theirs)."""
    from embodichain_core.plugins.gym_tasks import managed_entry_points

    providers = managed_entry_points(uid)
    if providers is None:
        return False
    if _entry(cls) in providers:
        REGISTERED_ENVS.setdefault(uid, EnvSpec(uid, cls, max_episode_steps, dict(kwargs)))
    else:
        warnings.warn(
            f"env id {uid!r} is provided by installed plugins ({', '.join(providers)}); "
            f"register_env keeps theirs and ignores {_entry(cls)}",
            stacklevel=3,
        )
    return True


def register_env(
    uid: str, max_episode_steps: Optional[int] = None, override: bool = False, **kwargs: Any
) -> Callable[[type], type]:
    """Class decorator registering ``uid`` with gymnasium.

    Re-registering the same class (its module being imported again by gymnasium)
    is a no-op; another class under a taken id warns and keeps the first unless
    ``override=True``. An id that installed plugins provide (see
    :mod:`embodichain_core.plugins.gym_tasks`) is never replaced, even with
    ``override=True``: its bare id may be shared by several plugins, and their
    namespaced ids (``<plugin>/<id>``) are what picks one. ``kwargs`` must be
    JSON-serialisable default constructor args.
    """
    try:
        json.dumps(kwargs)
    except TypeError as err:
        raise RuntimeError(f"register_env({uid!r}): kwargs must be JSON-serialisable: {err}") from err

    def wrap(cls: type) -> type:
        from embodichain_core.envs.embodied_env import EmbodiedEnv

        if not (isinstance(cls, type) and issubclass(cls, EmbodiedEnv)):
            raise TypeError(f"register_env({uid!r}) decorates EmbodiedEnv subclasses, got {cls!r}")
        if _provided_by_plugins(uid, cls, kwargs, max_episode_steps):
            return cls
        existing = gym.envs.registry.get(uid)
        if existing is not None and existing.entry_point == _entry(cls) and not override:
            # gymnasium imported the module of a plugin-registered task: same class
            REGISTERED_ENVS.setdefault(uid, EnvSpec(uid, cls, max_episode_steps, dict(kwargs)))
            if existing.vector_entry_point is None:
                existing.vector_entry_point = functools.partial(make_vec_env, _entry(cls))
            return cls
        if existing is not None and not override:
            warnings.warn(
                f"env id {uid!r} is already registered by {existing.entry_point}; keeping it "
                f"(pass override=True to replace it)",
                stacklevel=2,
            )
            return cls
        gym.envs.registry.pop(uid, None)
        defaults = dict(kwargs)
        if max_episode_steps is not None:
            defaults["_registered_max_episode_steps"] = int(max_episode_steps)
        gym.register(
            uid,
            entry_point=_entry(cls),
            disable_env_checker=True,
            order_enforce=False,
            vector_entry_point=functools.partial(make_vec_env, _entry(cls)),
            kwargs=defaults,
        )
        gym.envs.registry[uid] = batched_spec(gym.envs.registry[uid])  # unbatched sync/async sub-envs
        REGISTERED_ENVS[uid] = EnvSpec(uid, cls, max_episode_steps, dict(kwargs))
        return cls

    return wrap
