"""Named registries filled by plugins: functors, robots, solvers, sensors, assets, tasks, commands.

A :class:`Registry` maps names to :class:`Entry` objects. An entry's target is an
object or a lazy ``"module:attr"`` string imported on first :meth:`Registry.get`.
Names are owned by their providers: two plugins may register the same name, and each
entry keeps its qualified name ``"<provider>:<name>"`` (see
:mod:`embodichain_core.plugins.names`). A bare name provided by several plugins is
ambiguous (:class:`AmbiguousNameError`, naming every provider and the qualified
forms); an unknown name raises :class:`UnknownNameError` listing the closest matches.

Example:
    >>> reg = Registry("functors", noun="functor")
    >>> _ = reg.add("randomize_light", "my_pkg.events:randomize_light", provider="my-plugin")
    >>> reg.get("randomise_light")
    Traceback (most recent call last):
    ...
    embodichain_core.plugins.entries.UnknownNameError: unknown functor 'randomise_light'. Did you mean 'randomize_light'?

The typed register objects handed to the hooks wrap these registries; they live
with the hook specifications in :mod:`embodichain_core.plugins.hookspecs`; the task
registry, which mirrors tasks into gymnasium, lives in
:mod:`embodichain_core.plugins.gym_tasks`.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator

from embodichain_core.plugins.entries import (
    AmbiguousNameError,
    DuplicateRegistrationError,
    Entry,
    RegistryError,
    TargetImportError,
    UnknownNameError,
    check_target_string,
    describe_target,
    first_doc_line,
    import_target,
    is_lazy_target,
)
from embodichain_core.plugins.names import SEPARATOR, pick_by_priority, qualified, split_qualified
from embodichain_core.utils.suggest import closest, did_you_mean

__all__ = [
    "Entry",
    "Registry",
    "RegistryError",
    "AmbiguousNameError",
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


def _identity(name: str) -> str:
    return name


def class_name_key(name: str) -> str:
    """Case-insensitive key that also accepts a trailing ``Cfg`` (``DexforceW1Cfg``)."""
    key = name.lower()
    return key[:-3] if key.endswith("cfg") and len(key) > 3 else key


class Registry:
    """Names -> :class:`Entry` of one kind, owned by their providers.

    Two providers may register the same name: both entries are kept, each under its
    qualified name ``"<provider>:<name>"``. A bare name resolves when one provider
    registered it, or when ``EMBODICHAIN_PLUGIN_PRIORITY`` lists one of its providers;
    otherwise it is ambiguous (:class:`AmbiguousNameError`).

    Args:
        kind: registry kind (``"functors"``, ``"robots"`` ...).
        noun: singular word used in messages (default: ``kind`` without the ``s``).
        key: maps a name to its lookup key (default: exact names).
    """

    def __init__(self, kind: str, *, noun: str | None = None, key: Callable[[str], str] | None = None):
        self.kind = kind
        self.noun = noun or (kind[:-1] if kind.endswith("s") else kind)
        self._key = key or _identity
        #: (provider, key) -> entry, in registration order.
        self._entries: dict[tuple[str, str], Entry] = {}

    def add(
        self, name: str, target: Any, provider: str, meta: dict[str, Any] | None = None, *, lazy: bool | None = None
    ) -> Entry:
        """Add an entry; re-adding an identical entry is a no-op.

        Raises:
            DuplicateRegistrationError: ``provider`` already registered ``name`` with
                another target (another provider's entry of that name is no conflict).
            ValueError: empty name, a name with ``":"``, or a malformed lazy target.
        """
        self._check_name(name, provider)
        entry = Entry(name, target, provider, meta, lazy=lazy, noun=self.noun)
        if entry.lazy:
            check_target_string(target, f"{self.noun} {name!r} from {provider!r}")
        old = self._entries.get((provider, self._key(name)))
        if old is not None:
            if old.same_as(entry):
                return old
            raise DuplicateRegistrationError(
                self.noun, name, old.provider, provider, "one provider cannot register a name twice"
            )
        self._store(entry)
        return entry

    def _check_name(self, name: Any, provider: str) -> None:
        if not isinstance(name, str) or not name:
            raise ValueError(f"{self.noun} names must be non-empty strings, got {name!r} from {provider!r}")
        if SEPARATOR in name:
            raise ValueError(
                f"{self.noun} {name!r} from {provider!r}: names cannot contain {SEPARATOR!r} "
                f"(it separates the provider in qualified names)"
            )

    def _store(self, entry: Entry) -> None:
        self._entries[(entry.provider, self._key(entry.name))] = entry

    def _unstore(self, entry: Entry) -> None:
        del self._entries[(entry.provider, self._key(entry.name))]

    def remove(self, name: str, provider: str | None = None) -> Entry | None:
        """Remove and return an entry (``None`` when absent).

        ``name`` may be qualified; a bare name provided by several plugins needs
        ``provider`` (else :class:`AmbiguousNameError`).
        """
        split = self._split(name)
        if split is not None:
            provider, name = split
        found = self.find(name, use_priority=False) if provider is None else self.find_own(provider, name)
        if found is not None:
            self._unstore(found)
        return found

    def find_own(self, provider: str, name: str) -> Entry | None:
        """``provider``'s entry named ``name`` (bare), or ``None``; never ambiguous."""
        return self._entries.get((provider, self._key(name))) if isinstance(name, str) else None

    def providers(self) -> list[str]:
        """Every provider with at least one entry, sorted."""
        return sorted({provider for provider, _ in self._entries})

    def providers_of(self, name: str) -> list[str]:
        """The providers of the bare ``name``, sorted."""
        return sorted(e.provider for e in self._candidates(name))

    def _candidates(self, name: str) -> list[Entry]:
        key = self._key(name)
        return [e for (_, k), e in self._entries.items() if k == key]

    def _split(self, name: str) -> tuple[str, str] | None:
        """``(provider, bare)`` for a qualified ``name`` of a provider of this registry."""
        return split_qualified(name, self.providers())

    def find(self, name: str, *, use_priority: bool = True) -> Entry | None:
        """The entry for ``name`` (bare or qualified), or ``None``.

        Raises:
            AmbiguousNameError: a bare name provided by several plugins, none of
                them preferred by ``EMBODICHAIN_PLUGIN_PRIORITY``.
        """
        if not isinstance(name, str):
            return None
        split = self._split(name)
        if split is not None:
            return self.find_own(*split)
        candidates = self._candidates(name)
        if len(candidates) <= 1:
            return candidates[0] if candidates else None
        chosen = pick_by_priority([e.provider for e in candidates]) if use_priority else None
        if chosen is None:
            raise self.ambiguous(name, candidates)
        return next(e for e in candidates if e.provider == chosen)

    def ambiguous(self, name: str, candidates: list[Entry] | None = None) -> AmbiguousNameError:
        """The error for a bare ``name`` provided by several plugins."""
        entries = sorted(candidates or self._candidates(name), key=lambda e: e.provider)
        return AmbiguousNameError(
            self.noun, name, [e.provider for e in entries], [self.qualified_name(e) for e in entries]
        )

    def qualified_name(self, entry: Entry) -> str:
        """The name that always resolves to ``entry`` (``"<provider>:<name>"``)."""
        return qualified(entry.provider, entry.name)

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
            msg = (
                f"unknown {self.noun} {name!r}: no {self.kind} are registered; install a plugin "
                f"providing them (see `embodichain list plugins`)"
            )
            return UnknownNameError(msg, name, [])
        split = self._split(name) if isinstance(name, str) else None
        if split is not None:
            own = [self.qualified_name(e) for e in self.by_provider(split[0])]
            hint = did_you_mean(name, own) or f" See `embodichain list {self.kind} --provider {split[0]}`."
            return UnknownNameError(
                f"{split[0]!r} provides no {self.noun} {split[1]!r}.{hint}", name, closest(name, own)
            )
        provider, sep, _ = str(name).partition(SEPARATOR)
        if sep and provider:
            hint = did_you_mean(provider, self.providers()) or f" Providers: {', '.join(self.providers())}."
            return UnknownNameError(
                f"unknown {self.noun} {name!r}: no plugin named {provider!r} provides {self.kind}.{hint}",
                name,
                closest(provider, self.providers()),
            )
        hint = did_you_mean(name, names) or f" See `embodichain list {self.kind}`."
        return UnknownNameError(f"unknown {self.noun} {name!r}.{hint}", name, closest(name, names))

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
        providers: dict[str, list[Entry]] = {}
        for (_, key), entry in self._entries.items():
            providers.setdefault(key, []).append(entry)
        return {
            group[0].name: sorted(e.provider for e in group)
            for group in sorted(providers.values(), key=lambda g: g[0].name)
            if len(group) > 1
        }

    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str):
            return False
        split = self._split(name)
        if split is not None:
            return (split[0], self._key(split[1])) in self._entries
        return bool(self._candidates(name))

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"<Registry {self.kind}: {len(self)} entries>"


#: Registry kinds, in the order their hooks are called.
KINDS = ("commands", "assets", "robots", "solvers", "sensors", "functors", "tasks")


def new_registries() -> dict[str, Registry]:
    """A fresh, empty registry of every kind."""
    from embodichain_core.plugins.gym_tasks import TaskRegistry

    return {
        "functors": Registry("functors"),
        "robots": Registry("robots", key=class_name_key),
        "solvers": Registry("solvers", key=class_name_key),
        "sensors": Registry("sensors", key=class_name_key),
        "assets": Registry("assets", noun="asset root"),
        "tasks": TaskRegistry("tasks", noun="task"),
        "commands": Registry("commands"),
    }
