"""Name clashes: plugin names of entry points, and names several plugins register.

Two kinds of clash are detected and reported, never resolved by load order:

* **entry point names.** pluggy (and ``importlib.metadata`` users in general) key
  plugins by entry point name, so a second distribution declaring the entry point
  ``embodichain-functors`` would silently replace or drop the first. Here every
  plugin is named after its *distribution* (PEP 503-normalized), so both load; the
  clash is reported with a :class:`~embodichain_core.plugins.names.NameClashWarning`
  naming both distributions, and by ``embodichain list plugins``.
* **registered names.** Two plugins registering one name in a registry: both entries
  stay (qualified names ``<plugin>:<name>``); the bare name is ambiguous. See
  :func:`name_clashes`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from embodichain_core.plugins.names import canonical_name, join_names

if TYPE_CHECKING:
    from embodichain_core.plugins.registry import Registry

__all__ = ["NameClash", "name_clashes", "name_entry_points", "entry_point_clashes", "describe_clash"]


@dataclass(frozen=True)
class NameClash:
    """One bare name registered by several plugins.

    Attributes:
        kind: the registry kind (``"functors"``, ``"tasks"``, ...).
        name: the bare name.
        providers: the plugins registering it, sorted.
        qualified: the name that resolves to each provider's entry, in ``providers`` order
            (``<plugin>:<name>``; ``<namespace>/<id>`` for tasks).
    """

    kind: str
    name: str
    providers: tuple[str, ...]
    qualified: tuple[str, ...] = field(default=())

    def __str__(self) -> str:
        return describe_clash(self)


def describe_clash(clash: NameClash) -> str:
    """``"functor 'x' is provided by 'a' and 'b' (use 'a:x' or 'b:x')"``."""
    noun = clash.kind[:-1] if clash.kind.endswith("s") else clash.kind
    providers = join_names([repr(p) for p in clash.providers])
    forms = join_names([repr(q) for q in clash.qualified], "or")
    return f"{noun} {clash.name!r} is provided by {providers} (use {forms})"


def name_clashes(registries: Mapping[str, Registry], provider: str | None = None) -> list[NameClash]:
    """Every bare name registered by several plugins, by kind then name.

    Args:
        registries: kind -> registry (a plugin manager's ``registries``).
        provider: only the clashes this plugin takes part in.
    """
    found: list[NameClash] = []
    for kind, registry in registries.items():
        for name, providers in registry.clashes().items():
            if provider is not None and provider not in providers:
                continue
            entries = [registry.find_own(p, name) for p in providers]
            qualified = tuple(registry.qualified_name(e) for e in entries if e is not None)
            found.append(NameClash(kind, name, tuple(providers), qualified))
    return found


def _dist_name(ep: Any) -> str:
    dist = getattr(ep, "dist", None)
    name = getattr(dist, "name", None) if dist is not None else None
    return canonical_name(name) if isinstance(name, str) and name else ep.name


def name_entry_points(eps: Sequence[Any]) -> list[tuple[str, Any]]:
    """``(plugin name, entry point)`` pairs, sorted by plugin name: the load order.

    A plugin is named after its distribution; an entry point without a distribution
    keeps its own name. A distribution declaring several entry points names the one
    called after it ``<dist>`` and the others ``<dist>.<entry point name>``.
    """
    by_dist: dict[str, list[Any]] = {}
    for ep in eps:
        by_dist.setdefault(_dist_name(ep), []).append(ep)
    named: list[tuple[str, Any]] = []
    for dist, group in by_dist.items():
        for ep in group:
            alone = len(group) == 1 or canonical_name(ep.name) == dist
            named.append((dist if alone else f"{dist}.{canonical_name(ep.name)}", ep))
    return sorted(named, key=lambda pair: (pair[0], pair[1].name, str(getattr(pair[1], "value", ""))))


def entry_point_clashes(named: Sequence[tuple[str, Any]]) -> dict[str, list[str]]:
    """Entry point names declared by several plugins -> those plugins' names (sorted)."""
    plugins: dict[str, set[str]] = {}
    for plugin, ep in named:
        plugins.setdefault(ep.name, set()).add(plugin)
    return {ep_name: sorted(names) for ep_name, names in sorted(plugins.items()) if len(names) > 1}
