"""Resolve asset names such as ``"CircleTableSimple/circle_table_simple.ply"`` to files.

Search order of :func:`get_data_path`:

1. an absolute path (``~`` expanded) is returned unchanged when it exists;
2. ``$EMBODICHAIN_DATA_ROOT/<name>`` (default root ``~/.cache/embodichain_data``);
3. roots added at runtime with :func:`register_data_root`, newest last;
4. data roots that plugins registered in the ``assets`` registry, in load order (plugins
   load sorted by name, so the order never depends on how they were installed).

A name qualified by a plugin, ``"<plugin>:<relative path>"`` (``"embodichain-assets:
CircleTableSimple/circle_table_simple.ply"``), is searched only in the roots that plugin
registered. The prefix must be the name of a plugin that registered a data root; any other
text before a ``:`` is part of an ordinary name.

A name that is found nowhere raises :class:`DataPathNotFoundError`, whose message lists the roots
searched and the closest existing names. A trailing slash is kept, so folder names resolve to
folder paths ending with ``/`` (``"TableWare/tableware/fork/"``).
"""

from __future__ import annotations

import os
from typing import Any, Iterable

from embodichain_core.utils.suggest import closest

ENV_DATA_ROOT = "EMBODICHAIN_DATA_ROOT"
DEFAULT_DATA_ROOT = os.path.join("~", ".cache", "embodichain_data")
_SUGGEST_DEPTH = 3
_SUGGEST_LIMIT = 20000

_runtime_roots: list[str] = []


class DataPathNotFoundError(FileNotFoundError):
    """An asset name could not be resolved against any data root.

    Attributes:
        name: the name asked for.
        roots: every root searched, in order.
        suggestions: existing relative names that look like ``name``.
    """

    def __init__(self, name: str, roots: list[str], suggestions: list[str], reason: str = ""):
        self.name = name
        self.roots = roots
        self.suggestions = suggestions
        lines = [reason or f"Data path {name!r} was not found."]
        lines.append("Searched roots:" if roots else "No data root is configured.")
        lines += [f"  - {r}" + ("" if os.path.isdir(r) else " (missing)") for r in roots]
        if suggestions:
            lines.append("Closest existing names: " + ", ".join(repr(s) for s in suggestions))
        lines.append(
            f"Set ${ENV_DATA_ROOT}, or add a root from your plugin with the embodichain_register_assets hook "
            "(docs/assets.md)."
        )
        super().__init__("\n".join(lines))


def register_data_root(path: str | os.PathLike[str]) -> str:
    """Add a directory to search after ``$EMBODICHAIN_DATA_ROOT`` (idempotent).

    Example:
        >>> register_data_root("/opt/my_assets")  # doctest: +SKIP
        '/opt/my_assets'
    """
    root = os.path.abspath(os.path.expanduser(os.fspath(path)))
    if root not in _runtime_roots:
        _runtime_roots.append(root)
    return root


def unregister_data_root(path: str | os.PathLike[str]) -> None:
    """Remove a root added with :func:`register_data_root` (no error when absent)."""
    root = os.path.abspath(os.path.expanduser(os.fspath(path)))
    if root in _runtime_roots:
        _runtime_roots.remove(root)


def env_data_root() -> str:
    """``$EMBODICHAIN_DATA_ROOT``, or ``~/.cache/embodichain_data`` when it is unset."""
    value = os.environ.get(ENV_DATA_ROOT) or DEFAULT_DATA_ROOT
    return os.path.abspath(os.path.expanduser(value))


def data_roots() -> list[str]:
    """Every data root in search order (existing or not), without duplicates."""
    roots = [env_data_root(), *_runtime_roots, *_plugin_roots()]
    return list(dict.fromkeys(roots))


def get_data_path(name: str | os.PathLike[str]) -> str:
    """Resolve an asset name to an existing file or folder path.

    Args:
        name: an absolute path, or a path relative to a data root.

    Returns:
        The path; a folder name given with a trailing slash keeps it.

    Raises:
        DataPathNotFoundError: the name exists under no root (the message lists the roots and
            the closest existing names).

    Example:
        >>> get_data_path("TableWare/tableware/fork/")  # doctest: +SKIP
        '/home/me/.cache/embodichain_data/TableWare/tableware/fork/'
    """
    name = os.fspath(name)
    expanded = os.path.expanduser(name)
    if os.path.isabs(expanded):
        if os.path.exists(expanded):
            return expanded
        parent = os.path.dirname(expanded.rstrip("/")) or "/"
        siblings = os.listdir(parent) if os.path.isdir(parent) else []
        hint = closest(os.path.basename(expanded.rstrip("/")), siblings)
        raise DataPathNotFoundError(
            name, [], [os.path.join(parent, h) for h in hint], f"Absolute path {name!r} does not exist."
        )
    relative = name[2:] if name.startswith("./") else name
    provider, relative = _split_provider(relative)
    roots = data_roots() if provider is None else _plugin_roots(provider)
    for root in roots:
        candidate = os.path.join(root, relative)
        if os.path.exists(candidate):
            return candidate
    raise DataPathNotFoundError(name, roots, _suggest(relative, roots))


def _suggest(name: str, roots: Iterable[str]) -> list[str]:
    """Existing relative names under ``roots`` (depth <= 3) that look like ``name``."""
    names: list[str] = []
    for root in roots:
        names.extend(_walk_names(root, _SUGGEST_DEPTH))
    depth = name.rstrip("/").count("/") + 1
    same_depth = [n for n in names if n.rstrip("/").count("/") + 1 == depth]
    return closest(name, same_depth) or closest(name, names)


def _walk_names(root: str, max_depth: int) -> list[str]:
    """Relative file names and folder names (with a trailing ``/``) under ``root``."""
    if not os.path.isdir(root):
        return []
    out: list[str] = []
    for current, dirs, files in os.walk(root):
        rel = os.path.relpath(current, root)
        level = 0 if rel == "." else rel.count(os.sep) + 1
        prefix = "" if rel == "." else rel.replace(os.sep, "/") + "/"
        dirs.sort()
        out += [prefix + d + "/" for d in dirs] + [prefix + f for f in sorted(files)]
        if level + 1 >= max_depth:
            dirs[:] = []
        if len(out) > _SUGGEST_LIMIT:
            break
    return out


def _split_provider(name: str) -> tuple[str | None, str]:
    """``(plugin, relative)`` for ``"<plugin>:<relative>"`` naming a plugin with data roots."""
    prefix, sep, rest = name.partition(":")
    return (prefix, rest) if sep and prefix in _asset_registry().providers() else (None, name)


def _plugin_roots(provider: str | None = None) -> list[str]:
    """Data roots registered by plugins (only ``provider``'s when given), in load order."""
    from embodichain_core.plugins import get_asset_root

    entries = [e for e in _asset_registry().ordered_entries() if provider in (None, e.provider)]
    return [os.path.abspath(os.path.expanduser(os.fspath(get_asset_root(e)))) for e in entries]


def _asset_registry() -> Any:
    """The plugin host's ``assets`` registry (loading the plugins first)."""
    from embodichain_core.plugins import manager

    return manager.get_registry("assets")
