"""embodichain-core: configuration-driven robot-learning environments on MuJoCo.

Importing the package is cheap: it loads the installed plugins' registrations
(lazy strings), which registers their task ids with gymnasium, so
``gym.make("<plugin task id>")`` works after ``import embodichain_core``. The
heavy modules (torch, mujoco) load on first use of the names below.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "EmbodiedEnv": "embodichain_core.envs",
    "EmbodiedEnvCfg": "embodichain_core.envs",
    "BaseEnv": "embodichain_core.envs",
    "EnvCfg": "embodichain_core.envs",
    "register_env": "embodichain_core.envs",
    "configclass": "embodichain_core.utils.configclass",
    "MISSING": "embodichain_core.utils.configclass",
    "get_data_path": "embodichain_core.sim.data",
    "load_gym_config": "embodichain_core.config.loader",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'embodichain_core' has no attribute {name!r}")


def _load_plugins() -> None:
    from embodichain_core.plugins.manager import load_plugins

    load_plugins()


_load_plugins()
