"""``register_env``: register an env class as a task from a script, through the tasks hook.

A task is registered one way: the ``embodichain_register_tasks`` hook (docs/plugins.md).
``register_env`` is a decorator for scripts and notebooks that runs that hook for you: the
module defining the class becomes a runtime plugin (named after the module) registering the
task, so ``gym.make``, ``gym.make_vec``, ``embodichain list tasks``, ``embodichain run-env``
and the episode limit treat it as an installed plugin's task.

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

from embodichain_core.plugins import load_plugins, register_plugin, unregister_plugin
from embodichain_core.plugins.hookspecs import TaskRegister, hookimpl
from embodichain_core.plugins.registry import DuplicateRegistrationError, describe_target

#: A module's registrations: task id -> (env class, episode limit, default constructor kwargs).
_Tasks = dict[str, tuple[type, Optional[int], dict[str, Any]]]


class _ModuleTasks:
    """The runtime plugin of one module's ``register_env`` calls: its tasks hook."""

    def __init__(self, tasks: _Tasks) -> None:
        self.tasks = tasks

    @hookimpl
    def embodichain_register_tasks(self, register: TaskRegister) -> None:
        for uid, (env_cls, limit, kwargs) in self.tasks.items():
            register(uid, env_cls, max_episode_steps=limit, kwargs=kwargs)


def register_env(
    uid: str, max_episode_steps: Optional[int] = None, override: bool = False, **kwargs: Any
) -> Callable[[type], type]:
    """Class decorator registering a top-level ``BaseEnv`` subclass as the task ``uid``.

    An id an installed plugin (or another module) provides stays theirs: the class is left
    out, with a warning naming the provider unless that provider registers this very class
    (as ``embodichain-tasks`` does for the tutorial module that calls ``register_env``). A
    module registering a second class under one of its ids is an error, as for any plugin,
    unless ``override=True`` replaces its earlier class. ``kwargs`` are JSON-serialisable
    default constructor arguments.

    Raises:
        TypeError: not a ``BaseEnv`` subclass, or defined inside a function.
        DuplicateRegistrationError: the module registered another class as ``uid`` already.
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
    pm = load_plugins()
    # the class itself is the target: its module may not be importable by name (a script run
    # as __main__, a test file in a folder with a hyphen)
    name, target = cls.__module__, describe_target(cls)
    if pm.get_plugin(name) is not None and not isinstance(pm.get_plugin(name), _ModuleTasks):
        name += ".register_env"  # the module is a plugin of its own
    others = [e for e in pm.registry("tasks").ordered_entries() if e.name == uid and e.provider != name]
    if others:
        if all(e.target_repr != target for e in others):
            providers = ", ".join(sorted({e.provider for e in others}))
            warnings.warn(
                f"task {uid!r} is provided by {providers}; register_env keeps theirs and ignores {target}", stacklevel=3
            )
        return
    if "<locals>" in cls.__qualname__:
        raise TypeError(
            f"register_env({uid!r}): {cls.__qualname__} is defined inside a function; other processes (Ray "
            f"workers, dataset replay) find a task by 'module:Class', so define the class at the top level of "
            f"its module"
        )
    plugin = pm.get_plugin(name)
    tasks: _Tasks = dict(plugin.tasks) if plugin is not None else {}
    old = describe_target(tasks[uid][0]) if uid in tasks else target
    if old != target and not override:
        raise DuplicateRegistrationError(
            f"task {uid!r} is registered twice by {name!r} (with {old!r} and {target!r}); one provider cannot "
            f"register a name twice (pass override=True to replace it)"
        )
    tasks[uid] = (cls, limit, kwargs)
    if plugin is not None:
        unregister_plugin(name)
    register_plugin(_ModuleTasks(tasks), name=name)
