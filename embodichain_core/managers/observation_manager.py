"""Observation manager: ``add`` and ``modify`` functors on the nested observation dict."""

from __future__ import annotations

from typing import Any

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import ObservationCfg
from embodichain_core.managers.manager_base import ManagerBase
from embodichain_core.managers.param_rules import check_param_types


def get_nested(obs: dict, name: str) -> Any:
    """Value at ``a/b/c`` in a nested dict; ``KeyError`` names the missing level."""
    node: Any = obs
    for part in name.split("/"):
        if not isinstance(node, dict) or part not in node:
            have = list(node.keys()) if isinstance(node, dict) else []
            raise KeyError(f"observation {name!r} does not exist (at {part!r}; available: {have})")
        node = node[part]
    return node


_PARTS: dict[str, list[str]] = {}  # "a/b/c" -> its parts, split once per name


def set_nested(obs: dict, name: str, value: Any) -> None:
    """Write ``value`` at ``a/b/c``, creating intermediate dicts."""
    parts = _PARTS.get(name)
    if parts is None:
        parts = _PARTS[name] = name.split("/")
    node = obs
    for part in parts[:-1]:
        node = node.setdefault(part, {})
    node[parts[-1]] = value


class ObservationManager(ManagerBase[ObservationCfg]):
    """Extends the default ``robot``/``sensor`` observation with functor outputs.

    Modes run in the order of their first appearance; functors in declaration order.
    """

    section = "observations"
    kind = "observation"
    cfg_type = ObservationCfg
    min_argc = 2

    def _check(self, func: Any, cfg: ObservationCfg, where: str) -> None:
        # not ``is MISSING``: configs are deep-copied, which copies the sentinel too
        if not isinstance(cfg.name, str) or not cfg.name:
            raise ConfigError(
                join_path(where, "name"), "an observation functor needs a 'name' (e.g. 'object/cube_pose')"
            )
        if cfg.mode not in ("add", "modify"):
            raise ConfigError(join_path(where, "mode"), f"mode must be 'add' or 'modify', got {cfg.mode!r}")
        super()._check(func, cfg, where)
        check_param_types(func, cfg.params, where, self.min_argc)

    def compute(self, obs: dict) -> dict:
        """Apply every functor to ``obs`` (in place) and return it.

        Raises:
            ConfigError: a ``modify`` functor names an observation that does not
                exist. The env computes its first observation when it is built (for
                the observation space), so this is a build-time error.
        """
        for entry in self.entries.values():
            name = entry.cfg.name
            if entry.cfg.mode == "add":
                set_nested(obs, name, entry(self._env, obs))
                continue
            try:
                data = get_nested(obs, name)
            except KeyError as err:
                raise ConfigError(
                    join_path(entry.path, "name"),
                    f"{err.args[0]}; mode 'modify' changes an existing observation (use mode 'add' to create one)",
                ) from None
            out = entry(self._env, data)
            if out is not None and out is not data:
                set_nested(obs, name, out)
        return obs
