"""Registries of what plugins provide, and the lookup errors. Two plugins may register one
name: each entry stays reachable as ``<plugin>/<name>`` and the bare name is ambiguous.
``:`` only separates a lazy ``"module:attr"`` target, imported on first use.
"""

from __future__ import annotations

import importlib
import inspect
import re
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from embodichain_core.utils.suggest import closest, did_you_mean

#: Separates the plugin from the name in a qualified name (``embodichain-functors/randomize_light``).
SEPARATOR = "/"


class RegistryError(Exception):
    """Base class of registry errors."""

    def __str__(self) -> str:  # KeyError would repr() the message
        return str(self.args[0]) if self.args else ""


class DuplicateRegistrationError(RegistryError, ValueError):
    """One provider registered a name twice with different targets."""


class AmbiguousNameError(RegistryError, LookupError, ValueError):
    """A bare name several plugins provide: ``providers`` and the qualified ``choices``."""

    def __init__(self, message: str, name: str, providers: Sequence[str], choices: Sequence[str]):
        super().__init__(message)
        self.name, self.providers, self.choices = name, list(providers), list(choices)


class UnknownNameError(RegistryError, KeyError, ValueError):
    """An unknown name was looked up; ``matches`` holds the closest known names."""

    def __init__(self, message: str, name: str = "", matches: Sequence[str] = ()):
        super().__init__(message)
        self.name, self.matches = name, list(matches)


class TargetImportError(RegistryError, ImportError):
    """A lazy ``"module:attr"`` target could not be imported."""


def join_names(items: Sequence[str], word: str = "and") -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"`` (``word`` replaces ``and``)."""
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} {word} {items[-1]}"


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
    lines = [line.strip() for line in (inspect.getdoc(obj) or "").splitlines() if line.strip()]
    return lines[0] if lines else ""


_UNSET: Any = object()


class Entry:
    """``name`` -> ``target`` (an object or a lazy ``"module:attr"``) from plugin ``provider``."""

    def __init__(self, name: str, target: Any, provider: str, meta: dict | None, lazy: bool | None, noun: str):
        self.name, self.target, self.provider, self.noun = name, target, provider, noun
        self.meta: dict[str, Any] = dict(meta or {})
        self.lazy = is_lazy_target(target) if lazy is None else lazy
        self._value = _UNSET if self.lazy else target

    @property
    def resolved(self) -> bool:
        """Whether the target has been imported (always True for eager targets)."""
        return self._value is not _UNSET

    def resolve(self) -> Any:
        """The target object, imported on first call (:class:`TargetImportError` naming the entry)."""
        if self._value is _UNSET:
            self._value = self._import(self.target)
            if "description" in self.meta and not self.meta["description"]:
                self.meta["description"] = first_doc_line(self._value)
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
        """``meta["description"]``, else the resolved target's first docstring line."""
        text = self.meta.get("description") or ""
        if not text and self.resolved and callable(self._value):
            text = first_doc_line(self._value)
        return str(text)

    def __repr__(self) -> str:
        return f"Entry({self.name!r}, {self.target_repr!r}, provider={self.provider!r})"


@dataclass(frozen=True)
class NameClash:
    """A bare name several plugins register: its ``providers`` and ``qualified`` names."""

    kind: str
    name: str
    providers: tuple[str, ...]
    qualified: tuple[str, ...]

    def __str__(self) -> str:
        noun = self.kind.removesuffix("s")
        forms = join_names([repr(q) for q in self.qualified], "or")
        return f"{noun} {self.name!r} is provided by {join_names([repr(p) for p in self.providers])} (use {forms})"


class Registry:
    """Names -> :class:`Entry` of one ``kind``; ``key`` maps a name to its lookup key."""

    def __init__(self, kind: str, *, noun: str | None = None, key: Callable[[str], str] | None = None):
        self.kind = kind
        self.noun = noun or kind.removesuffix("s")
        self._key: Callable[[str], str] = key or str
        #: (provider, key) -> entry, in registration order.
        self._entries: dict[tuple[str, str], Entry] = {}

    def add(
        self, name: str, target: Any, provider: str, meta: dict | None = None, *, lazy: bool | None = None
    ) -> Entry:
        """Add an entry (an identical one again is a no-op)."""
        if not isinstance(name, str) or not name or SEPARATOR in name or ":" in name:
            raise ValueError(
                f"{self.noun} {name!r} from {provider!r}: names are non-empty strings without '/' or ':' "
                f"('/' separates the plugin in qualified names, ':' an import path)"
            )
        entry = Entry(name, target, provider, meta, lazy, self.noun)
        if entry.lazy:
            check_target_string(target, f"{self.noun} {name!r} from {provider!r}")
        return self.merge(entry)

    def merge(self, entry: Entry) -> Entry:
        """Store a checked entry (see :meth:`add`); returns the stored one."""
        old = self._entries.get((entry.provider, self._key(entry.name)))
        if old is not None and (old.target_repr, repr(old.meta)) != (entry.target_repr, repr(entry.meta)):
            raise DuplicateRegistrationError(
                f"{self.noun} {entry.name!r} is registered twice by {entry.provider!r} "
                f"(with {old.target_repr!r} and {entry.target_repr!r}); one provider cannot register a name twice"
            )
        return self._entries.setdefault((entry.provider, self._key(entry.name)), entry)

    def remove(self, name: str, provider: str | None = None) -> Entry | None:
        """Remove and return an entry (``None`` when absent); ``name`` may be qualified."""
        found = self.find(name) if provider is None else self.find_own(provider, name)
        if found is not None:
            del self._entries[(found.provider, self._key(found.name))]
        return found

    def find_own(self, provider: str, name: str) -> Entry | None:
        """``provider``'s entry named ``name`` (bare), or ``None``."""
        return self._entries.get((provider, self._key(name)))

    def providers(self) -> list[str]:
        """Every provider with at least one entry, sorted."""
        return sorted({provider for provider, _ in self._entries})

    def providers_of(self, name: str) -> list[str]:
        """The providers of the bare ``name``, sorted."""
        return sorted(e.provider for e in self._candidates(name))

    def _candidates(self, name: str) -> list[Entry]:
        key = self._key(name)
        return [e for (_, k), e in self._entries.items() if k == key]

    def _split(self, name: str, sep: str = SEPARATOR) -> tuple[str, str] | None:
        """``(provider, bare)`` for ``"<plugin><sep><bare>"`` naming a provider of this registry."""
        prefix, found, bare = name.partition(sep)
        providers = {namespace(p): p for p in self.providers()} | {p: p for p in self.providers()}
        return (providers[prefix], bare) if found and bare and prefix in providers else None

    def find(self, name: str) -> Entry | None:
        """The entry for ``name`` (bare or qualified), or ``None``; :class:`AmbiguousNameError`
        for a bare name several plugins provide or a qualified name spelled with ``:``."""
        if not isinstance(name, str):
            return None
        split = self._split(name)
        if split is not None:
            return self.find_own(*split)
        old = self._split(name, ":")
        if old is not None:
            choice = f"{namespace(old[0])}{SEPARATOR}{old[1]}"
            raise AmbiguousNameError(
                f"{self.noun} {name!r}: ':' separates an import path ('module:attr'); the qualified name of "
                f"{old[0]!r}'s {self.noun} {old[1]!r} is written with '/': use {choice!r}",
                name,
                [old[0]],
                [choice],
            )
        candidates = self._candidates(name)
        if len(candidates) > 1:
            raise self.ambiguous(name, candidates)
        return candidates[0] if candidates else None

    def ambiguous(self, name: str, candidates: list[Entry]) -> AmbiguousNameError:
        """The error for a bare ``name`` provided by several plugins."""
        entries = sorted(candidates, key=lambda e: e.provider)
        providers, choices = [e.provider for e in entries], [self.qualified_name(e) for e in entries]
        message = (
            f"{self.noun} {name!r} is ambiguous: it is provided by {join_names([repr(p) for p in providers])}. "
            f"Use a qualified name: {join_names([repr(c) for c in choices], 'or')}."
        )
        return AmbiguousNameError(message, name, providers, choices)

    def qualified_name(self, entry: Entry) -> str:
        """The name that always resolves to ``entry`` (``"<plugin>/<name>"``)."""
        return f"{namespace(entry.provider)}{SEPARATOR}{entry.name}"

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
        if not self._entries:
            return UnknownNameError(
                f"unknown {self.noun} {name!r}: no {self.kind} are registered; install a plugin "
                f"providing them (see `embodichain list plugins`)",
                name,
            )
        split = self._split(name)
        if split is not None:
            own = [self.qualified_name(e) for e in self.by_provider(split[0])]
            hint = did_you_mean(name, own) or f" See `embodichain list {self.kind} --provider {split[0]}`."
            return UnknownNameError(
                f"{split[0]!r} provides no {self.noun} {split[1]!r}.{hint}", name, closest(name, own)
            )
        prefix, sep, _ = name.partition(SEPARATOR)
        if sep:
            hint = did_you_mean(prefix, self.providers()) or f" Providers: {', '.join(self.providers())}."
            message = f"unknown {self.noun} {name!r}: no plugin named {prefix!r} provides {self.kind}.{hint}"
            return UnknownNameError(message, name, closest(prefix, self.providers()))
        hint = did_you_mean(name, self.names()) or f" See `embodichain list {self.kind}`."
        return UnknownNameError(f"unknown {self.noun} {name!r}.{hint}", name, closest(name, self.names()))

    def names(self) -> list[str]:
        """Registered bare names, sorted, each once (however many providers)."""
        first: dict[str, str] = {}
        for (_, key), entry in self._entries.items():
            first.setdefault(key, entry.name)
        return sorted(first.values())

    def qualified_names(self) -> list[str]:
        """The qualified name of every entry, sorted."""
        return sorted(self.qualified_name(e) for e in self._entries.values())

    def entries(self) -> list[Entry]:
        """Entries sorted by name, then provider."""
        return sorted(self._entries.values(), key=lambda e: (e.name, e.provider))

    def ordered_entries(self) -> list[Entry]:
        """Entries in registration order (deterministic: plugins load sorted by name)."""
        return list(self._entries.values())

    def by_provider(self, provider: str) -> list[Entry]:
        """Entries registered by ``provider``."""
        return [e for e in self.entries() if e.provider == provider]

    def clashes(self) -> dict[str, list[str]]:
        """Bare names provided by several plugins -> their providers (sorted)."""
        return {c.name: list(c.providers) for c in self.name_clashes()}

    def name_clashes(self) -> list[NameClash]:
        """Every bare name several plugins provide, by name."""
        groups: dict[str, list[Entry]] = {}
        for (_, key), entry in self._entries.items():
            groups.setdefault(key, []).append(entry)
        found = []
        for group in sorted(groups.values(), key=lambda g: g[0].name):
            if len(group) > 1:
                group = sorted(group, key=lambda e: e.provider)
                providers = tuple(e.provider for e in group)
                found.append(NameClash(self.kind, group[0].name, providers, tuple(map(self.qualified_name, group))))
        return found

    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str):
            return False
        split = self._split(name)
        return self.find_own(*split) is not None if split is not None else bool(self._candidates(name))

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)
