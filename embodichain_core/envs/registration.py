"""``register_env``: register an env class as a task from a script, through the tasks hook.

A task is registered one way: the ``embodichain_register_tasks`` hook (see
docs/plugins.md). ``register_env`` is a decorator for scripts and notebooks that runs that
hook for you: the module defining the class becomes a runtime plugin (named after the
module) registering the task, so ``gym.make``, ``gym.make_vec``, ``embodichain list
tasks`` and the episode limit behave as for an installed plugin's task.

Example:
    >>> @register_env("MyTask-v0", max_episode_steps=200)
    ... class MyTask(EmbodiedEnv):
    ...     ...
    >>> env = gym.make("MyTask-v0", cfg=MyTaskCfg(num_envs=8))
"""

from __future__ import annotations

import json
import warnings
from typing import Any, Callable, Optional

from embodichain_core.plugins.hookspecs import hookimpl
from embodichain_core.plugins.registry import describe_target

#: Task id -> the class ``register_env`` registered under it.
REGISTERED_ENVS: dict[str, type] = {}


class _ModuleTasks:
    """The runtime plugin of one module's ``register_env`` calls."""

    def __init__(self) -> None:
        self.tasks: dict[str, tuple[type, Optional[int], dict[str, Any]]] = {}

    @hookimpl
    def embodichain_register_tasks(self, register: Any) -> None:
        for uid, (target, limit, kwargs) in self.tasks.items():
            register(uid, target, max_episode_steps=limit, kwargs=kwargs)


def register_env(
    uid: str, max_episode_steps: Optional[int] = None, override: bool = False, **kwargs: Any
) -> Callable[[type], type]:
    """Class decorator registering the env class as the task ``uid``.

    An id that an installed plugin (or another module) provides is never replaced, even
    with ``override=True``: a warning names the provider and the class is left out (the
    same class registered again is a silent no-op). The module's own earlier class under
    ``uid`` is replaced with ``override=True`` (a warning and no change otherwise); so is an
    id gymnasium has from outside the plugins. ``kwargs`` are JSON-serialisable default
    constructor arguments.
    """
    try:
        json.dumps(kwargs)
    except TypeError as err:
        raise RuntimeError(f"register_env({uid!r}): kwargs must be JSON-serialisable: {err}") from err

    def wrap(cls: type) -> type:
        from embodichain_core.envs.base_env import BaseEnv

        if not (isinstance(cls, type) and issubclass(cls, BaseEnv)):
            raise TypeError(f"register_env({uid!r}) decorates BaseEnv or EmbodiedEnv subclasses, got {cls!r}")
        _register(uid, cls, max_episode_steps, dict(kwargs), override)
        return cls

    return wrap


def _register(uid: str, cls: type, limit: Optional[int], kwargs: dict[str, Any], override: bool) -> None:
    import gymnasium

    from embodichain_core.plugins import load_plugins, register_plugin, unregister_plugin

    pm = load_plugins()
    # the class itself is the target: its module may not be importable by name (a test file
    # in a folder with a hyphen, a script run as __main__); ``target`` is how it is shown
    name, target = cls.__module__, describe_target(cls)
    others = [
        e
        for e in pm.registry("tasks").ordered_entries()
        if e.name == uid and e.provider not in (name, f"{name}.register_env")
    ]
    if others:
        if all(e.target_repr != target for e in others):
            providers = ", ".join(sorted({e.provider for e in others}))
            warnings.warn(
                f"env id {uid!r} is provided by installed plugins ({providers}); register_env keeps theirs and "
                f"ignores {target}",
                stacklevel=3,
            )
        return
    if "<locals>" in cls.__qualname__:
        raise TypeError(
            f"register_env({uid!r}): {cls.__qualname__} is defined inside a function; other processes (Ray "
            f"workers, dataset replay) find a task by 'module:Class', so define the class at the top level of "
            f"its module"
        )
    if pm.get_plugin(name) is not None and not isinstance(pm.get_plugin(name), _ModuleTasks):
        name += ".register_env"  # the module is a plugin of its own
    plugin = pm.get_plugin(name) or _ModuleTasks()
    old = plugin.tasks.get(uid)
    if old is not None and describe_target(old[0]) != target and not override:
        warnings.warn(
            f"env id {uid!r} is already registered by {describe_target(old[0])}; keeping it (pass override=True to replace it)",
            stacklevel=3,
        )
        return
    foreign = gymnasium.registry.get(uid)
    if foreign is not None and not getattr(foreign, "embodichain_task", False) and override:
        del gymnasium.registry[uid]
    plugin.tasks[uid] = (cls, limit, kwargs)
    if pm.get_plugin(name) is not None:
        unregister_plugin(name)
    register_plugin(plugin, name=name)
    REGISTERED_ENVS[uid] = cls
