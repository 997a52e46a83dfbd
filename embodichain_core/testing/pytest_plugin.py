"""pytest plugin for embodichain plugin authors (entry point ``pytest11``).

Installed with ``embodichain-core``, so every test session gets these fixtures:

* ``plugin_manager``: an isolated plugin manager with fresh, empty registries
  (only the core's built-ins; installed entry points are *not* loaded). The
  global plugin state, and gymnasium's registry, are restored after the test.
* ``register_plugin``: ``register_plugin(obj_or_module, name=None) -> str``
  registers a plugin into that isolated manager and runs its register hooks.
* the env fixtures of :mod:`embodichain_core.testing.env_checks` (``make_env``,
  ``check_batched_env``) when that module is available.

Example:
    >>> def test_my_plugin(register_plugin, plugin_manager):  # doctest: +SKIP
    ...     import my_plugin.plugin
    ...     register_plugin(my_plugin.plugin)
    ...     assert "my_functor" in plugin_manager.registry("functors")

This module must import cheaply: everything else is imported inside fixtures.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType
from typing import TYPE_CHECKING, Any, Callable, Iterator

import pytest

if TYPE_CHECKING:
    from embodichain_core.plugins.manager import EmbodichainPluginManager

ENV_CHECKS_MODULE = "embodichain_core.testing.env_checks"


@pytest.fixture
def plugin_manager() -> Iterator["EmbodichainPluginManager"]:
    """An isolated plugin manager (built-ins only), restored after the test."""
    from embodichain_core.plugins.manager import isolated_plugins

    with isolated_plugins() as pm:
        yield pm


@pytest.fixture
def register_plugin(plugin_manager: "EmbodichainPluginManager") -> Callable[..., str]:
    """A function registering a plugin object or module into the isolated manager.

    Returns:
        ``register_plugin(obj, name=None) -> str`` returning the plugin's name. A
        misspelled hook or a failing register hook raises right away.
    """
    from embodichain_core.plugins.manager import register_plugin as _register

    def register(obj: Any, name: str | None = None) -> str:
        return _register(obj, name=name)

    return register


def _env_checks() -> ModuleType | None:
    """The env fixtures module when it exists (it is optional)."""
    try:
        if importlib.util.find_spec(ENV_CHECKS_MODULE) is None:
            return None
    except (ImportError, ValueError):
        return None
    return importlib.import_module(ENV_CHECKS_MODULE)


def pytest_configure(config: pytest.Config) -> None:
    """Register the env fixtures of ``testing.env_checks`` when available."""
    manager = config.pluginmanager
    if manager.has_plugin(ENV_CHECKS_MODULE):
        return
    try:
        module = _env_checks()
    except Exception as err:  # a broken optional module must not break every session
        warning = pytest.PytestConfigWarning(f"cannot import {ENV_CHECKS_MODULE}: {err!r}")
        config.issue_config_time_warning(warning, stacklevel=2)
        return
    if module is not None and not manager.is_registered(module):
        manager.register(module, ENV_CHECKS_MODULE)
