"""Qualified names, provider priority and the ambiguity error.

Every registered thing is owned by its provider (for an installed plugin: its
distribution name, PEP 503-normalized, such as ``embodichain-functors``) and has the
qualified name ``<provider>:<name>``. Tasks also have the gymnasium id
``<namespace>/<id>``, whose namespace is the provider name with every character
gymnasium does not allow in a namespace replaced by ``-``.

A *bare* name resolves when exactly one provider registered it. When several did,
it is ambiguous: lookups raise :class:`AmbiguousNameError`, naming every provider and
the qualified forms, unless the environment variable ``EMBODICHAIN_PLUGIN_PRIORITY``
(comma-separated provider names, highest priority first) lists one of them, in which
case the first listed provider wins. Nothing is ever chosen by load order. The error
class, :class:`~embodichain_core.plugins.registry.AmbiguousNameError`, lives with the
registries.

Example:
    >>> split_qualified("embodichain-functors:randomize_light", {"embodichain-functors"})
    ('embodichain-functors', 'randomize_light')
    >>> split_qualified("my_pkg.events:randomize_light", {"embodichain-functors"}) is None
    True
"""

from __future__ import annotations

import os
import re
from typing import Collection, Sequence

__all__ = [
    "PRIORITY_ENV",
    "NameClashWarning",
    "join_names",
    "canonical_name",
    "gym_namespace",
    "plugin_priority",
    "pick_by_priority",
    "qualified",
    "split_qualified",
]

#: Environment variable listing providers in priority order (comma-separated).
PRIORITY_ENV = "EMBODICHAIN_PLUGIN_PRIORITY"
SEPARATOR = ":"
_NOT_IN_NAMESPACE = re.compile(r"[^\w-]+")


def join_names(items: Sequence[str], word: str = "and") -> str:
    """``"a"``, ``"a and b"``, ``"a, b and c"`` (``word`` replaces ``and``)."""
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} {word} {items[-1]}"


def canonical_name(name: str) -> str:
    """A distribution name normalized as PEP 503 does (``Foo_Bar`` -> ``foo-bar``)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def gym_namespace(provider: str) -> str:
    """The gymnasium namespace of ``provider`` (characters other than ``\\w`` and ``-`` become ``-``)."""
    return _NOT_IN_NAMESPACE.sub("-", provider).strip("-") or "plugin"


def qualified(provider: str, name: str) -> str:
    """``"<provider>:<name>"``."""
    return f"{provider}{SEPARATOR}{name}"


def split_qualified(name: str, providers: Collection[str]) -> tuple[str, str] | None:
    """``(provider, bare name)`` when ``name`` is ``"<provider>:<bare>"`` with a known provider.

    The rule that tells a qualified name from a ``"module:attr"`` import path: the text
    before the first ``:`` must be one of ``providers`` (plugin names). Anything else is
    not a qualified name (``None``).
    """
    provider, sep, bare = name.partition(SEPARATOR)
    if not sep or not bare or provider not in providers:
        return None
    return provider, bare


def plugin_priority() -> list[str]:
    """Providers listed in ``EMBODICHAIN_PLUGIN_PRIORITY``, highest priority first."""
    raw = os.environ.get(PRIORITY_ENV, "")
    return [p.strip() for p in raw.split(",") if p.strip()]


def pick_by_priority(providers: Collection[str], priority: Sequence[str] | None = None) -> str | None:
    """The first provider of ``priority`` (default: the env var) among ``providers``, or ``None``."""
    for provider in plugin_priority() if priority is None else priority:
        if provider in providers:
            return provider
        if canonical_name(provider) in providers:
            return canonical_name(provider)
    return None


class NameClashWarning(UserWarning):
    """Two plugins (or a plugin and gymnasium) claim one name; both are kept, nothing is disabled."""
