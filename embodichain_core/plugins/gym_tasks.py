"""The task registry and its mirror in gymnasium's registry.

Every task is registered with gymnasium twice:

* under its namespaced id ``<namespace>/<id>`` (``embodichain-tasks/PushCube-v1``),
  which always builds that provider's task;
* under its bare id (``PushCube-v1``). With one provider, the bare id points at that
  provider's class. With several, it points at a :class:`BareTaskEntryPoint` that
  resolves the id when ``gymnasium.make`` runs: through ``EMBODICHAIN_PLUGIN_PRIORITY``
  when it lists a provider, else by raising the
  :class:`~embodichain_core.plugins.registry.AmbiguousNameError`.

gymnasium gets string entry points (imported only by ``gymnasium.make``),
``disable_env_checker=True``, ``order_enforce=False`` and never
``max_episode_steps`` (the episode limit lives inside the env, as a kwarg), in a
:class:`~embodichain_core.gym_vector.BatchedEnvSpec` (``gym.make_vec`` in the ``"sync"``
and ``"async"`` modes stacks unbatched single envs). An id
gymnasium already knows from elsewhere (not from a plugin) is left alone, with a
:class:`~embodichain_core.plugins.names.NameClashWarning` unless it has the same
entry point.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any

from embodichain_core.plugins.names import NameClashWarning, gym_namespace, split_qualified
from embodichain_core.plugins.registry import Entry, Registry, describe_target

__all__ = ["TaskRegistry", "BareTaskEntryPoint", "managed_entry_points"]

#: gym id -> entry points of its providers, for the ids an attached TaskRegistry put there.
_MANAGED: dict[str, tuple[str, ...]] = {}


def managed_entry_points(gym_id: str) -> tuple[str, ...] | None:
    """The entry points of the plugins providing ``gym_id``, or ``None`` when no plugin manages it."""
    return _MANAGED.get(gym_id)


class BareTaskEntryPoint:
    """gymnasium entry point of a bare task id that several plugins provide.

    Resolved when the env is made: the provider ``EMBODICHAIN_PLUGIN_PRIORITY``
    prefers, else an :class:`~embodichain_core.plugins.registry.AmbiguousNameError`.
    """

    def __init__(self, registry: Registry, task_id: str):
        self.registry, self.task_id = registry, task_id

    def _target(self) -> tuple[Any, dict[str, Any]]:
        from gymnasium.envs.registration import load_env_creator

        entry = self.registry.entry(self.task_id)
        return load_env_creator(entry.target), dict(entry.meta.get("kwargs") or {})

    def __call__(self, **kwargs: Any) -> Any:
        creator, defaults = self._target()
        return creator(**{**defaults, **kwargs})

    def make_vec(self, num_envs: int = 1, **kwargs: Any) -> Any:
        """``gymnasium.make_vec`` of the resolved provider's task."""
        from embodichain_core.gym_vector import make_vec_env

        entry = self.registry.entry(self.task_id)
        defaults = dict(entry.meta.get("kwargs") or {})
        return make_vec_env(entry.target, num_envs=num_envs, **{**defaults, **kwargs})

    @property
    def cfg_cls(self) -> Any:
        """The resolved env class's ``cfg_cls`` (``None`` while the id is ambiguous)."""
        try:
            return getattr(self._target()[0], "cfg_cls", None)
        except Exception:  # the error surfaces, with its message, in gymnasium.make
            return None

    def __repr__(self) -> str:
        return f"<ambiguous task {self.task_id!r}: {', '.join(self.registry.providers_of(self.task_id))}>"


class TaskRegistry(Registry):
    """Task registry that mirrors every task into gymnasium's registry (see the module doc).

    An id another task registry put into gymnasium (the outer manager, while
    ``isolated_plugins`` runs) is shadowed, and restored when this registry lets it go
    (:meth:`release_gym`, or when its last provider is removed).
    """

    def __init__(self, kind: str = "tasks", **kwargs: Any):
        super().__init__(kind, **kwargs)
        #: gym id -> (spec, provider entry points) this registry put into gymnasium.
        self._owned: dict[str, tuple[Any, tuple[str, ...]]] = {}
        #: gym id -> (spec, entry points) of another task registry, replaced by ours.
        self._shadowed: dict[str, tuple[Any, tuple[str, ...]]] = {}

    def _check_name(self, name: Any, provider: str) -> None:
        super()._check_name(name, provider)
        if "/" in name:
            raise ValueError(
                f"task {name!r} from {provider!r}: register the bare id; the gymnasium "
                f"namespace is the provider's ({gym_namespace(provider)}/...)"
            )

    def qualified_name(self, entry: Entry) -> str:
        """The namespaced gym id ``<namespace>/<id>``."""
        return f"{gym_namespace(entry.provider)}/{entry.name}"

    def _split(self, name: str) -> tuple[str, str] | None:
        namespace, sep, bare = name.partition("/")
        if sep:
            providers = {gym_namespace(p): p for p in self.providers()}
            return (providers[namespace], bare) if namespace in providers and bare else None
        return split_qualified(name, self.providers())

    def _store(self, entry: Entry) -> None:
        entry.meta["gym_id"] = self.qualified_name(entry)
        super()._store(entry)
        self._put(entry.meta["gym_id"], [entry])
        self._sync_bare(entry.name)

    def _unstore(self, entry: Entry) -> None:
        super()._unstore(entry)
        self._drop(entry.meta["gym_id"])
        self._sync_bare(entry.name)

    def _sync_bare(self, name: str) -> None:
        candidates = self._candidates(name)
        if candidates:
            self._put(name, candidates)
        else:
            self._drop(name)

    def _put(self, gym_id: str, entries: list[Entry]) -> None:
        import gymnasium
        from embodichain_core.gym_vector import BatchedEnvSpec, make_vec_env

        existing = gymnasium.registry.get(gym_id)
        if existing is not None and gym_id not in self._owned:
            if gym_id not in _MANAGED:
                self._report_foreign(gym_id, existing, entries)
                return
            self._shadowed[gym_id] = (existing, _MANAGED[gym_id])
        if len(entries) == 1:
            target, kwargs = entries[0].target, entries[0].meta["kwargs"]
            vector: Any = functools.partial(make_vec_env, target)
        else:
            target, kwargs = BareTaskEntryPoint(self, gym_id), {}
            vector = target.make_vec
        spec = BatchedEnvSpec(
            gym_id,
            entry_point=target,
            disable_env_checker=True,
            order_enforce=False,
            max_episode_steps=None,
            kwargs=dict(kwargs),
            vector_entry_point=vector,
        )
        self._owned[gym_id] = (spec, tuple(e.target for e in entries))
        gymnasium.registry[gym_id] = spec
        _MANAGED[gym_id] = self._owned[gym_id][1]

    def _drop(self, gym_id: str) -> None:
        spec, _ = self._owned.pop(gym_id, (None, ()))
        if spec is None:
            return
        import gymnasium

        if gymnasium.registry.get(gym_id) is spec:
            del gymnasium.registry[gym_id]
        _MANAGED.pop(gym_id, None)
        if gym_id in self._shadowed:
            gymnasium.registry[gym_id], _MANAGED[gym_id] = self._shadowed.pop(gym_id)

    def _report_foreign(self, gym_id: str, existing: Any, entries: list[Entry]) -> None:
        theirs = describe_target(existing.entry_point)
        if len(entries) == 1 and theirs == entries[0].target_repr:
            return  # the same class, registered by its own module: keep gymnasium's spec
        ids = ", ".join(repr(self.qualified_name(e)) for e in entries)
        warnings.warn(
            f"gymnasium id {gym_id!r} is already registered outside the embodichain plugins "
            f"(entry point {theirs!r}); it is left as it is. Use {ids} for the plugin "
            f"task{'s' if len(entries) > 1 else ''}.",
            NameClashWarning,
            stacklevel=2,
        )

    def release_gym(self) -> None:
        """Take this registry's ids out of gymnasium, restoring the ids they shadowed.

        The entries stay in the registry; ``isolated_plugins`` calls this on exit.
        """
        for gym_id in list(self._owned):
            self._drop(gym_id)
