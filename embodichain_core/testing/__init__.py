"""Testing helpers for embodichain plugin authors.

Public helpers (imported lazily, so ``import embodichain_core.testing`` is cheap):

* :func:`isolated_plugins`: context manager with a fresh plugin manager and empty
  registries (built-ins only), restoring the global state afterwards.
* :func:`register_plugin`: register a plugin object or module at runtime.
* :func:`patch_entry_points`: choose the installed plugins (entry points) a test's
  plugin loading sees, e.g. stand-ins for a plugin that fails to import.
* :func:`check_name_clashes`: register a plugin next to the *installed* plugins and
  report (raise :class:`NameClashError`) every name it shares with them, e.g.
  ``check_name_clashes(my_plugin, name="embodichain-myplugin")``.
* :func:`without_host_arrays`, :func:`cpu_device_route`: run a consumer, or a whole env
  on backend ``warp``, on the torch (GPU) state route on the CPU
  (:mod:`embodichain_core.testing.device_paths`).
* ``make_env`` / ``check_batched_env``: env checks from
  :mod:`embodichain_core.testing.env_checks`, when that module is available.

The pytest fixtures live in :mod:`embodichain_core.testing.pytest_plugin`, which
pytest loads automatically (entry point ``pytest11``).
"""

from __future__ import annotations

import importlib
from typing import Any

_PLUGIN_HELPERS = {
    "isolated_plugins": "embodichain_core.plugins.manager",
    "register_plugin": "embodichain_core.plugins.manager",
    "unregister_plugin": "embodichain_core.plugins.manager",
    "check_name_clashes": "embodichain_core.testing.clashes",
    "NameClashError": "embodichain_core.testing.clashes",
    "patch_entry_points": "embodichain_core.testing.entry_points",
    "without_host_arrays": "embodichain_core.testing.device_paths",
    "cpu_device_route": "embodichain_core.testing.device_paths",
}
_ENV_HELPERS = ("make_env", "check_batched_env")

__all__ = [*_PLUGIN_HELPERS, *_ENV_HELPERS]


def __getattr__(name: str) -> Any:
    if name in _PLUGIN_HELPERS:
        return getattr(importlib.import_module(_PLUGIN_HELPERS[name]), name)
    if name in _ENV_HELPERS:
        try:
            module = importlib.import_module("embodichain_core.testing.env_checks")
        except ImportError as err:
            raise AttributeError(f"{name} needs embodichain_core.testing.env_checks: {err}") from err
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
