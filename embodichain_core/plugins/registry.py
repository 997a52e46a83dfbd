"""Named registries filled by plugins: functors, robots, sensors, assets, tasks, commands.

A :class:`Registry` maps names to :class:`Entry` objects. An entry's target is an
object or a lazy ``"module:attr"`` string imported on first :meth:`Registry.get`.
Names are unique: a second registration raises :class:`DuplicateRegistrationError`
naming both providers; an unknown name raises :class:`UnknownNameError` listing the
closest matches.

Example:
    >>> reg = Registry("functors", noun="functor")
    >>> _ = reg.add("randomize_light", "my_pkg.events:randomize_light", provider="my-plugin")
    >>> reg.get("randomise_light")
    Traceback (most recent call last):
    ...
    embodichain_core.plugins.registry.UnknownNameError: unknown functor 'randomise_light'. Did you mean 'randomize_light'?

The typed register objects handed to the hooks wrap these registries; they live
with the hook specifications in :mod:`embodichain_core.plugins.hookspecs`.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any, Callable, Iterator

from embodichain_core.utils.suggest import closest, did_you_mean

__all__ = [
    "Entry",
    "Registry",
    "TaskRegistry",
    "RegistryError",
    "DuplicateRegistrationError",
    "UnknownNameError",
    "TargetImportError",
    "import_target",
    "describe_target",
    "is_lazy_target",
    "check_target_string",
    "class_name_key",
    "first_doc_line",
    "KINDS",
    "new_registries",
]


class RegistryError(Exception):
    """Base class of registry errors."""


class DuplicateRegistrationError(RegistryError, ValueError):
    """A name was registered twice; the message names both providers."""

    def __init__(self, noun: str, name: str, first: str, second: str, detail: str = ""):
        self.name, self.first_provider, self.second_provider = name, first, second
        msg = f"{noun} {name!r} is registered twice: by {first!r} and by {second!r}"
        super().__init__(msg + (f" ({detail})" if detail else ""))


class UnknownNameError(RegistryError, KeyError, ValueError):
    """An unknown name was looked up; ``matches`` holds the closest known names."""

    def __init__(self, message: str, name: str = "", matches: list[str] | None = None):
        super().__init__(message)
        self.name = name
        self.matches = list(matches or [])

    def __str__(self) -> str:  # KeyError would repr() the message
        return str(self.args[0])


class TargetImportError(RegistryError, ImportError):
    """A lazy ``"module:attr"`` target could not be imported."""


def is_lazy_target(value: Any) -> bool:
    """True for ``"module:attr"`` strings."""
    return isinstance(value, str) and ":" in value


def check_target_string(spec: str, what: str) -> None:
    """Raise ``ValueError`` unless ``spec`` looks like ``"package.module:attr.sub"``."""
    module, sep, attr = spec.partition(":")
    parts = module.split(".") + attr.split(".")
    if not sep or not all(p.isidentifier() for p in parts):
        raise ValueError(f"{what}: expected a 'module:attr' string, got {spec!r}")


def import_target(spec: str) -> Any:
    """Import ``"module:attr.sub"`` and return the attribute."""
    module_name, _, attr = spec.partition(":")
    obj: Any = importlib.import_module(module_name)
    for part in attr.split("."):
        obj = getattr(obj, part)
    return obj


def describe_target(target: Any) -> str:
    """``"module:qualname"`` for objects, the string itself for lazy targets."""
    if isinstance(target, str):
        return target
    module = getattr(target, "__module__", None)
    qualname = getattr(target, "__qualname__", None)
    if module and qualname:
        return f"{module}:{qualname}"
    return repr(target)


def first_doc_line(obj: Any) -> str:
    """The first non-empty docstring line of ``obj``, or ``""``."""
    doc = inspect.getdoc(obj) if obj is not None else None
    for line in (doc or "").splitlines():
        if line.strip():
            return line.strip()
    return ""


_UNSET: Any = object()


class Entry:
    """One registration: ``name`` -> ``target`` provided by ``provider``.

    Attributes:
        name: the registered name (as spelled by the provider).
        target: the object, or a lazy ``"module:attr"`` string.
        provider: the plugin name (for entry points: the distribution name).
        meta: extra data of the kind (``kind``/``category``/``description`` for functors...).
        lazy: whether ``target`` is imported on first :meth:`resolve`.
    """

    __slots__ = ("name", "target", "provider", "meta", "lazy", "noun", "_value", "_signature")

    def __init__(self, name: str, target: Any, provider: str, meta: dict[str, Any] | None = None,
                 *, lazy: bool | None = None, noun: str = "entry"):
        self.name, self.target, self.provider = name, target, provider
        self.meta: dict[str, Any] = dict(meta or {})
        self.lazy = is_lazy_target(target) if lazy is None else lazy
        self.noun = noun
        self._value = _UNSET if self.lazy else target
        self._signature = (provider, describe_target(target), repr(self.meta))

    @property
    def resolved(self) -> bool:
        """Whether the target has been imported (always True for eager targets)."""
        return self._value is not _UNSET

    def resolve(self) -> Any:
        """The target object, importing a lazy target on first call.

        Raises:
            TargetImportError: naming the entry and its provider.
        """
        if self._value is _UNSET:
            self._value = self._import(self.target)
            if "description" in self.meta and not self.meta["description"]:
                self.meta["description"] = first_doc_line(self._value)
        return self._value

    def resolve_meta(self, key: str) -> Any:
        """A meta value, importing it when it is a ``"module:attr"`` string."""
        value = self.meta[key]
        if is_lazy_target(value):
            value = self.meta[key] = self._import(value)
        return value

    def _import(self, spec: str) -> Any:
        try:
            return import_target(spec)
        except Exception as err:
            raise TargetImportError(
                f"cannot load {self.noun} {self.name!r} provided by {self.provider!r}: "
                f"importing {spec!r} failed with {type(err).__name__}: {err}"
            ) from err

    @property
    def target_repr(self) -> str:
        """The target as ``"module:attr"`` text."""
        return describe_target(self.target)

    @property
    def description(self) -> str:
        """``meta["description"]``, else the resolved target's first docstring line."""
        text = self.meta.get("description") or ""
        if not text and self.resolved and callable(self._value):
            text = first_doc_line(self._value)
        return str(text)

    def same_as(self, other: Entry) -> bool:
        """Same provider, target and meta (a harmless re-registration)."""
        return self._signature == other._signature

    def __repr__(self) -> str:
        return f"Entry({self.name!r}, {self.target_repr!r}, provider={self.provider!r})"


def _identity(name: str) -> str:
    return name


def class_name_key(name: str) -> str:
    """Case-insensitive key that also accepts a trailing ``Cfg`` (``DexforceW1Cfg``)."""
    key = name.lower()
    return key[:-3] if key.endswith("cfg") and len(key) > 3 else key


class Registry:
    """Names -> :class:`Entry` of one kind.

    Args:
        kind: registry kind (``"functors"``, ``"robots"`` ...).
        noun: singular word used in messages (default: ``kind`` without the ``s``).
        key: maps a name to its lookup key (default: exact names).
    """

    def __init__(self, kind: str, *, noun: str | None = None, key: Callable[[str], str] | None = None):
        self.kind = kind
        self.noun = noun or (kind[:-1] if kind.endswith("s") else kind)
        self._key = key or _identity
        self._entries: dict[str, Entry] = {}

    def add(self, name: str, target: Any, provider: str, meta: dict[str, Any] | None = None,
            *, lazy: bool | None = None) -> Entry:
        """Add an entry; re-adding an identical entry is a no-op.

        Raises:
            DuplicateRegistrationError: ``name`` exists from another provider or target.
            ValueError: empty name or malformed lazy target.
        """
        if not isinstance(name, str) or not name:
            raise ValueError(f"{self.noun} names must be non-empty strings, got {name!r} from {provider!r}")
        entry = Entry(name, target, provider, meta, lazy=lazy, noun=self.noun)
        if entry.lazy:
            check_target_string(target, f"{self.noun} {name!r} from {provider!r}")
        old = self._entries.get(self._key(name))
        if old is not None:
            if old.same_as(entry):
                return old
            raise DuplicateRegistrationError(self.noun, name, old.provider, provider)
        self._store(entry)
        return entry

    def _store(self, entry: Entry) -> None:
        self._entries[self._key(entry.name)] = entry

    def remove(self, name: str) -> Entry | None:
        """Remove and return the entry for ``name`` (``None`` when absent)."""
        return self._entries.pop(self._key(name), None)

    def find(self, name: str) -> Entry | None:
        """The entry for ``name`` or ``None``."""
        return self._entries.get(self._key(name)) if isinstance(name, str) else None

    def entry(self, name: str) -> Entry:
        """The entry for ``name``; raises :class:`UnknownNameError` with suggestions."""
        found = self.find(name)
        if found is None:
            raise self.unknown(name)
        return found

    def get(self, name: str) -> Any:
        """The (resolved) target registered as ``name``."""
        return self.entry(name).resolve()

    def unknown(self, name: str) -> UnknownNameError:
        """The error for an unknown ``name``, with the closest registered names."""
        names = self.names()
        if not names:
            msg = (f"unknown {self.noun} {name!r}: no {self.kind} are registered; install a plugin "
                   f"providing them (see `embodichain list plugins`)")
            return UnknownNameError(msg, name, [])
        hint = did_you_mean(name, names) or f" See `embodichain list {self.kind}`."
        return UnknownNameError(f"unknown {self.noun} {name!r}.{hint}", name, closest(name, names))

    def names(self) -> list[str]:
        """Registered names, sorted."""
        return sorted(e.name for e in self._entries.values())

    def entries(self) -> list[Entry]:
        """Entries sorted by name."""
        return sorted(self._entries.values(), key=lambda e: e.name)

    def by_provider(self, provider: str) -> list[Entry]:
        """Entries registered by ``provider``."""
        return [e for e in self.entries() if e.provider == provider]

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._key(name) in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"<Registry {self.kind}: {len(self)} entries>"


class TaskRegistry(Registry):
    """Task registry that mirrors every task into gymnasium's registry.

    gymnasium gets the string entry point (imported only by ``gymnasium.make``),
    ``disable_env_checker=True``, ``order_enforce=False`` and never
    ``max_episode_steps`` (the episode limit lives inside the env, as a kwarg).
    """

    def _store(self, entry: Entry) -> None:
        import gymnasium

        spec = gymnasium.registry.get(entry.name)
        if spec is None:
            import functools

            from embodichain_core.gym_vector import make_vec_env

            gymnasium.register(
                entry.name, entry_point=entry.target, disable_env_checker=True,
                order_enforce=False, max_episode_steps=None, kwargs=entry.meta["kwargs"],
                vector_entry_point=functools.partial(make_vec_env, entry.target),
            )
            entry.meta["gym_registered"] = True
        elif describe_target(spec.entry_point) != entry.target_repr:
            detail = f"gymnasium already has it with entry point {describe_target(spec.entry_point)!r}"
            raise DuplicateRegistrationError("task", entry.name, "gymnasium registry", entry.provider, detail)
        super()._store(entry)

    def remove(self, name: str) -> Entry | None:
        """Remove the entry and the gymnasium id this registry added for it."""
        entry = super().remove(name)
        if entry is not None and entry.meta.get("gym_registered"):
            import gymnasium

            gymnasium.registry.pop(entry.name, None)
        return entry


#: Registry kinds, in the order their hooks are called.
KINDS = ("commands", "assets", "robots", "sensors", "functors", "tasks")


def new_registries() -> dict[str, Registry]:
    """A fresh, empty registry of every kind."""
    return {
        "functors": Registry("functors"),
        "robots": Registry("robots", key=class_name_key),
        "sensors": Registry("sensors", key=class_name_key),
        "assets": Registry("assets", noun="asset root"),
        "tasks": TaskRegistry("tasks"),
        "commands": Registry("commands"),
    }
