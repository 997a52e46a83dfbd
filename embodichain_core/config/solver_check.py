"""Checks of a robot section's ``solver_cfg`` at config load (before the model is built).

``{part: {"class_type": name, ...}}``: every part must be one of ``control_parts`` and
every ``class_type`` a registered solver (bare or ``<plugin>/<name>``). Links and chains
need the compiled model; the robot checks them when it is built
(:mod:`embodichain_core.sim.entities.solvers`).
"""

from __future__ import annotations

from typing import Any, Mapping

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.utils.suggest import did_you_mean


def check_solver_cfg(cfg: Any, path: str) -> None:
    """Check ``cfg.solver_cfg`` of a robot config whose solvers come from the solver registry.

    Robot configs with their own ``build_solvers`` hook (procedural robot plugins) are skipped.

    Raises:
        ConfigError: not a mapping, an unknown part, or an unknown ``class_type``, at its path.
    """
    solver_cfg = getattr(cfg, "solver_cfg", None)
    if solver_cfg is None or callable(getattr(cfg, "build_solvers", None)):
        return
    from embodichain_core.sim.entities.solvers import part_entry, resolve_solver_class

    where = join_path(path, "solver_cfg")
    if not isinstance(solver_cfg, Mapping):
        raise ConfigError(where, f"expected a {{part: solver settings}} mapping, got {type(solver_cfg).__name__}")
    parts = dict(getattr(cfg, "control_parts", None) or {})
    for part, entry in solver_cfg.items():
        at = join_path(where, str(part))
        if part not in parts:
            hint = did_you_mean(str(part), parts) or " Define the part in control_parts first."
            raise ConfigError(at, f"unknown control part {part!r}.{hint}")
        resolve_solver_class(part_entry(entry, at).get("class_type"), join_path(at, "class_type"))
