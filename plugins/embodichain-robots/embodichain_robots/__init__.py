"""embodichain-robots: the DexForce W1 and a 7-DoF arm for embodichain-core.

Importing this package is cheap; the config classes load on first attribute
access (``embodichain_robots.DexforceW1Cfg``).

Example:
    >>> from embodichain_robots import DexforceW1Cfg
    >>> cfg = DexforceW1Cfg.from_dict({"uid": "dexforce_w1", "version": "v021"})
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "DexforceW1Cfg": "embodichain_robots.dexforce_w1.cfg",
    "SevenDofArmCfg": "embodichain_robots.seven_dof_arm.cfg",
    "IKSolverCfg": "embodichain_robots.kinematics.solver",
    "DLSSolver": "embodichain_robots.kinematics.solver",
    "SerialChain": "embodichain_robots.kinematics.chain",
    "MjDLSSolver": "embodichain_robots.kinematics.mj_solver",
    "build_part_solvers": "embodichain_robots.kinematics.factory",
    "ProceduralRobotCfg": "embodichain_robots.base_cfg",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'embodichain_robots' has no attribute {name!r}")
