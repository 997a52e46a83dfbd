"""``check_name_clashes``: check a plugin's names against the installed plugins.

The ``plugin_manager`` fixture isolates a test from the installed plugins, so a
plugin's own tests cannot see that another installed plugin registers the same
functor, task, robot, sensor, data root or command name. This helper loads every
installed plugin into a fresh manager (the plugin under test excluded, when it is
installed too), registers the plugin under test next to them, and reports each bare
name it shares with another plugin. Clashes never disable a plugin, but they make
the bare names ambiguous for users (see docs/plugins.md, "Names and clashes").

Example:
    >>> import embodichain_myplugin.plugin as plugin  # doctest: +SKIP
    >>> def test_no_name_clashes():  # doctest: +SKIP
    ...     check_name_clashes(plugin, name="embodichain-myplugin")
"""

from __future__ import annotations

import types
import warnings
from typing import Any, Iterable

from embodichain_core.plugins.manager import NameClash

__all__ = ["NameClashError", "check_name_clashes"]


class NameClashError(AssertionError):
    """Names of the plugin under test that installed plugins register too.

    Attributes:
        clashes: one :class:`~embodichain_core.plugins.NameClash` per shared name.
    """

    def __init__(self, plugin: str, clashes: list[NameClash]):
        self.clashes = clashes
        lines = [
            f"plugin {plugin!r} registers {len(clashes)} name(s) that installed plugins register too "
            f"(the bare names are ambiguous for users; rename them, or ask users for the qualified names):"
        ]
        lines += [f"  {clash}" for clash in clashes]
        super().__init__("\n".join(lines))


def check_name_clashes(
    plugin: Any, name: str | None = None, *, ignore: Iterable[str] = (), raise_on_clash: bool = True
) -> list[NameClash]:
    """Register ``plugin`` next to every installed plugin and report the names it shares.

    Args:
        plugin: the plugin module or object (what your entry point loads).
        name: its plugin name, normally your distribution name. Default: the name of
            the installed entry point that loads ``plugin``'s module, else the module name.
        ignore: bare names whose clashes are expected (deliberate overrides).
        raise_on_clash: raise :class:`NameClashError` when a clash is found (the default).

    Returns:
        The clashes (empty when every name of ``plugin`` is unique).

    Raises:
        NameClashError: on a clash, unless ``raise_on_clash`` is false. It names every
            clashing name, its providers and the qualified names.
        pluggy.PluginValidationError: ``plugin`` implements an unknown hook.
    """
    from embodichain_core.plugins.manager import NameClashWarning, PluginLoadWarning, isolated_plugins, register_plugin

    name = name or _installed_name(plugin) or _module_name(plugin)
    with warnings.catch_warnings():  # a broken unrelated plugin must not fail this check
        warnings.simplefilter("ignore", PluginLoadWarning)
        warnings.simplefilter("ignore", NameClashWarning)
        with isolated_plugins(load_entry_points=True, exclude={name}) as pm:
            register_plugin(plugin, name=name)
            clashes = pm.name_clashes(name)
    skipped = set(ignore)
    clashes = [clash for clash in clashes if clash.name not in skipped]
    if clashes and raise_on_clash:
        raise NameClashError(name, clashes)
    return clashes


def _installed_name(plugin: Any) -> str | None:
    """The plugin name of the installed entry point loading ``plugin``'s module, if any."""
    from embodichain_core.plugins import manager

    module = plugin.__name__ if isinstance(plugin, types.ModuleType) else getattr(plugin, "__module__", None)
    for plugin_name, ep in manager.named_entry_points():
        if module and ep.value.split(":")[0] == module:
            return plugin_name
    return None


def _module_name(plugin: Any) -> str:
    if isinstance(plugin, types.ModuleType):
        return plugin.__name__
    cls = plugin if isinstance(plugin, type) else type(plugin)
    return f"{cls.__module__}.{cls.__qualname__}"
