"""Registries of what plugins register, and the lookup errors. Every entry is reachable as
``<plugin>/<name>``; a bare name several plugins register is ambiguous. ``:`` only separates a
lazy ``"module:attr"`` target, imported on first use."""

from __future__ import annotations

import importlib
import inspect
import re
from typing import Any, Callable, Iterator, Sequence

from embodichain_core.utils.suggest import closest, did_you_mean

#: Separates the plugin from the name in a qualified name (``embodichain-functors/randomize_light``).
SEPARATOR = "/"


class DuplicateRegistrationError(ValueError):
    """One provider registered a name twice with different targets."""


class AmbiguousNameError(LookupError):
    """A bare name several plugins register; ``providers`` lists them."""

    def __init__(self, message: str, providers: Sequence[str] = ()):
        super().__init__(message)
        self.providers = list(providers)


class UnknownNameError(KeyError):
    """An unknown name; ``matches`` holds the closest registered names."""

    def __init__(self, message: str, matches: Sequence[str] = ()):
        super().__init__(message)
        self.matches = list(matches)

    def __str__(self) -> str:  # the message, not KeyError's quoted repr of it
        return str(self.args[0])


class TargetImportError(ImportError):
    """A lazy ``"module:attr"`` target could not be imported."""


def join_names(items: Sequence[str], word: str = "and") -> str:
    """``"'a'"``, ``"'a' and 'b'"``, ``"'a', 'b' and 'c'"`` (quoted; ``word`` replaces ``and``)."""
    quoted = [repr(item) for item in items]
    return quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} {word} {quoted[-1]}"


def namespace(provider: str) -> str:
    """The prefix of ``provider``'s qualified names (a valid gymnasium namespace)."""
    return re.sub(r"[^\w-]+", "-", provider).strip("-") or "plugin"


def is_lazy_target(value: Any) -> bool:
    """True for ``"module:attr"`` strings."""
    return isinstance(value, str) and ":" in value


def check_target_string(spec: str, what: str) -> None:
    """Raise ``ValueError`` unless ``spec`` looks like ``"package.module:attr.sub"``."""
    module, sep, attr = spec.partition(":")
    if not sep or not all(p.isidentifier() for p in module.split(".") + attr.split(".")):
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
    module, qualname = getattr(target, "__module__", None), getattr(target, "__qualname__", None)
    return f"{module}:{qualname}" if module and qualname else repr(target)


def first_doc_line(obj: Any) -> str:
    """The first non-empty docstring line of ``obj``, or ``""``."""
    return next((line.strip() for line in (inspect.getdoc(obj) or "").splitlines() if line.strip()), "")


class RegistryEntry:
    """``name`` -> ``target`` (an object, or a lazy ``"module:attr"``) from plugin ``provider``;
    ``meta`` holds the kind's extra values (a functor's ``kind``, a task's ``kwargs``, ...)."""

    def __init__(self, name: str, target: Any, provider: str, meta: dict | None, lazy: bool | None, noun: str):
        self.name, self.target, self.provider, self.noun = name, target, provider, noun
        self.meta: dict[str, Any] = dict(meta or {})
        self.lazy = is_lazy_target(target) if lazy is None else lazy
        self.resolved, self._value = not self.lazy, target  # resolved: the target has been imported

    def resolve(self) -> Any:
        """The target object, imported on first call (:class:`TargetImportError` naming the entry)."""
        if not self.resolved:
            self._value, self.resolved = self._import(self.target), True
        return self._value

    def resolve_meta(self, key: str) -> Any:
        """A meta value, importing it when it is a ``"module:attr"`` string."""
        if is_lazy_target(self.meta[key]):
            self.meta[key] = self._import(self.meta[key])
        return self.meta[key]

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
        """``meta["description"]``, else the imported target's first docstring line."""
        text = self.meta.get("description") or ""
        return str(text or (first_doc_line(self._value) if self.resolved and callable(self._value) else ""))

    def __repr__(self) -> str:
        return f"RegistryEntry({self.name!r}, {self.target_repr!r}, provider={self.provider!r})"


class Registry:
    """Names -> :class:`RegistryEntry` of one ``kind``; ``key`` maps a name to its lookup key."""

    def __init__(self, kind: str, *, noun: str | None = None, key: Callable[[str], str] | None = None):
        self.kind, self.noun = kind, noun or kind.removesuffix("s")
        self._key: Callable[[str], str] = key or str
        #: (provider, key) -> entry, in registration order (plugins load sorted by name).
        self._entries: dict[tuple[str, str], RegistryEntry] = {}

    def add(
        self, name: str, target: Any, provider: str, meta: dict | None = None, *, lazy: bool | None = None
    ) -> RegistryEntry:
        """Add an entry (an identical one again is a no-op); returns the stored one."""
        what = f"{self.noun} {name!r} from {provider!r}"
        if not isinstance(name, str) or not name or SEPARATOR in name or ":" in name:
            raise ValueError(
                f"{what}: names are non-empty strings without '/' or ':' "
                f"('/' separates the plugin in qualified names, ':' an import path)"
            )
        entry = RegistryEntry(name, target, provider, meta, lazy, self.noun)
        if entry.lazy:
            check_target_string(target, what)
        old = self._entries.setdefault((provider, self._key(name)), entry)
        if (old.target_repr, repr(old.meta)) != (entry.target_repr, repr(entry.meta)):
            raise DuplicateRegistrationError(
                f"{self.noun} {name!r} is registered twice by {provider!r} (with {old.target_repr!r} and "
                f"{entry.target_repr!r}); one provider cannot register a name twice"
            )
        return old

    def drop(self, provider: str) -> None:
        """Remove every entry of ``provider``."""
        self._entries = {k: e for k, e in self._entries.items() if e.provider != provider}

    def find(self, name: str) -> RegistryEntry | None:
        """The entry for ``name`` (bare or qualified), or ``None``; :class:`AmbiguousNameError`
        for a bare name several plugins register."""
        provider, bare = self._split(name) if isinstance(name, str) else (None, "")
        if provider is not None:
            return self._entries.get((provider, self._key(bare)))
        candidates = sorted(self._candidates(bare), key=lambda e: e.provider)
        if len(candidates) > 1:
            providers = [e.provider for e in candidates]
            raise AmbiguousNameError(
                f"{self.noun} {name!r} is ambiguous: it is provided by {join_names(providers)}. "
                f"Use a qualified name: {join_names([self.qualified_name(e) for e in candidates], 'or')}.",
                providers,
            )
        return candidates[0] if candidates else None

    def _candidates(self, name: str) -> list[RegistryEntry]:
        key = self._key(name)
        return [e for (_, k), e in self._entries.items() if k == key]

    def _split(self, name: str) -> tuple[str | None, str]:
        """``(provider, bare)`` for ``"<plugin>/<bare>"`` naming a provider here, else ``(None, name)``."""
        prefix, found, bare = name.partition(SEPARATOR)
        providers = {namespace(p): p for p in self.providers()} | {p: p for p in self.providers()}
        return (providers[prefix], bare) if found and bare and prefix in providers else (None, name)

    def entry(self, name: str) -> RegistryEntry:
        """The entry for ``name``; :class:`UnknownNameError` with the closest names."""
        found = self.find(name)
        if found is None:
            raise self.unknown(name)
        return found

    def unknown(self, name: str) -> UnknownNameError:
        """The error for an unknown ``name``, with the closest registered names (or plugins)."""
        if not self._entries:
            return UnknownNameError(
                f"unknown {self.noun} {name!r}: no {self.kind} are registered; install a plugin providing "
                "them (see `embodichain list plugins`)"
            )
        provider, bare = self._split(name)
        prefix, sep, _ = name.partition(SEPARATOR)
        if provider is not None:  # a known plugin, an unknown name: suggest among its names
            message, typed = f"{provider!r} provides no {self.noun} {bare!r}", name
            pool = [self.qualified_name(e) for e in self.by_provider(provider)]
        elif sep:  # an unknown plugin: suggest among the plugins
            typed, pool = prefix, self.providers()
            message = f"unknown {self.noun} {name!r}: no plugin named {prefix!r} provides {self.kind}"
        else:  # ':' is an import path's separator: a name written with it gets the qualified forms
            message, typed = f"unknown {self.noun} {name!r}", name
            pool = self.qualified_names() if ":" in name else self.names()
        listing = f"embodichain list {self.kind}" + (f" --provider {provider}" if provider else "")
        hint = did_you_mean(typed, pool) or f" See `{listing}`."
        return UnknownNameError(f"{message}.{hint}", closest(typed, pool))

    def get(self, name: str) -> Any:
        """The (imported) target registered as ``name``."""
        return self.entry(name).resolve()

    def qualified_name(self, entry: RegistryEntry) -> str:
        """The name that always resolves to ``entry`` (``"<plugin>/<name>"``)."""
        return f"{namespace(entry.provider)}{SEPARATOR}{entry.name}"

    def names(self) -> list[str]:
        """Registered bare names, sorted, each once (however many providers)."""
        return sorted({self._key(e.name): e.name for e in reversed(self.ordered_entries())}.values())

    def qualified_names(self) -> list[str]:
        """The qualified name of every entry, sorted."""
        return sorted(map(self.qualified_name, self._entries.values()))

    def entries(self) -> list[RegistryEntry]:
        """Entries sorted by name, then provider."""
        return sorted(self._entries.values(), key=lambda e: (e.name, e.provider))

    def ordered_entries(self) -> list[RegistryEntry]:
        """Entries in registration order."""
        return list(self._entries.values())

    def by_provider(self, provider: str) -> list[RegistryEntry]:
        """Entries registered by ``provider``."""
        return [e for e in self.entries() if e.provider == provider]

    def providers(self) -> list[str]:
        """Every provider with at least one entry, sorted."""
        return sorted({provider for provider, _ in self._entries})

    def providers_of(self, name: str) -> list[str]:
        """The providers of the bare ``name``, sorted."""
        return sorted(e.provider for e in self._candidates(name))

    def clashes(self) -> dict[str, list[str]]:
        """Bare names several plugins register -> their providers (sorted), by name."""
        providers = {name: self.providers_of(name) for name in self.names()}
        return {name: found for name, found in providers.items() if len(found) > 1}

    def __contains__(self, name: object) -> bool:
        try:
            return isinstance(name, str) and self.find(name) is not None
        except AmbiguousNameError:
            return True

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)
