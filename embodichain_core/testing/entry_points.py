"""``patch_entry_points``: choose the ``"embodichain"`` entry points the plugin host sees.

The plugin host finds plugins with ``importlib.metadata.entry_points(group="embodichain")``.
A test of loading (a plugin that fails to import, two distributions providing one name)
replaces or filters what that call returns for the rest of the test, through pytest's
``monkeypatch``; every other entry point group is left as it is.

Example:
    >>> def test_broken_plugin(monkeypatch):  # doctest: +SKIP
    ...     ep = types.SimpleNamespace(name="broken", value="broken.plugin", dist=None, load=fail)
    ...     patch_entry_points(monkeypatch, lambda installed: [ep])
    ...     with isolated_plugins(load_entry_points=True):
    ...         ...
"""

from __future__ import annotations

import importlib.metadata
from typing import Any, Callable

import pytest

from embodichain_core.plugins.manager import ENTRY_POINT_GROUP

__all__ = ["patch_entry_points"]


def patch_entry_points(monkeypatch: pytest.MonkeyPatch, select: Callable[[list[Any]], list[Any]]) -> None:
    """Until the test ends, the ``"embodichain"`` entry points are ``select(installed)``.

    Args:
        monkeypatch: the test's ``monkeypatch`` fixture (it undoes the change).
        select: gets the installed entry points of the group and returns those to use:
            a filter of them, or stand-ins with ``name``, ``value``, ``dist`` (``name``,
            ``version``; or ``None``) and ``load()``.
    """
    real = importlib.metadata.entry_points

    def entry_points(**params: Any) -> Any:
        found = real(**params)
        return select(list(found)) if params.get("group") == ENTRY_POINT_GROUP else found

    monkeypatch.setattr(importlib.metadata, "entry_points", entry_points)
