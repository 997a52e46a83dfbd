"""Registry entries, the registry errors and the helpers of lazy ``"module:attr"`` targets.

Re-exported by :mod:`embodichain_core.plugins.registry`, where most code imports them.
"""

from __future__ import annotations

import importlib
import inspect
from typing import Any, Sequence

from embodichain_core.plugins.names import PRIORITY_ENV, join_names

__all__ = [
    "Entry",
    "RegistryError",
    "AmbiguousNameError",
    "DuplicateRegistrationError",
    "UnknownNameError",
    "TargetImportError",
    "import_target",
    "describe_target",
    "is_lazy_target",
    "check_target_string",
    "first_doc_line",
]


class RegistryError(Exception):
    """Base class of registry errors."""


class DuplicateRegistrationError(RegistryError, ValueError):
    """One provider registered a name twice with different targets (names both registrations)."""

    def __init__(self, noun: str, name: str, first: str, second: str, detail: str = ""):
        self.name, self.first_provider, self.second_provider = name, first, second
        msg = f"{noun} {name!r} is registered twice: by {first!r} and by {second!r}"
        super().__init__(msg + (f" ({detail})" if detail else ""))


class AmbiguousNameError(RegistryError, LookupError, ValueError):
    """A bare name is provided by several plugins and no priority picks one.

    Attributes:
        name: the bare name asked for.
        providers: every provider of the name, sorted.
        choices: the qualified forms to use instead, one per provider.
    """

    def __init__(self, noun: str, name: str, providers: Sequence[str], choices: Sequence[str]):
        self.name, self.providers, self.choices = name, list(providers), list(choices)
        listed = join_names([repr(p) for p in self.providers])
        forms = join_names([repr(c) for c in self.choices], "or")
        super().__init__(
            f"{noun} {name!r} is ambiguous: it is provided by {listed}. Use a qualified name: "
            f"{forms}; or prefer one provider with {PRIORITY_ENV}={','.join(self.providers)} "
            f"(first listed wins)."
        )

    def __str__(self) -> str:
        return str(self.args[0])


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

    def __init__(
        self,
        name: str,
        target: Any,
        provider: str,
        meta: dict[str, Any] | None = None,
        *,
        lazy: bool | None = None,
        noun: str = "entry",
    ):
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
