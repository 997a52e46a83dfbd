"""Observation manager: ``add`` and ``modify`` functors on the nested observation dict."""

from __future__ import annotations

from typing import Any

from embodichain_core.config.checks import describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import ObservationCfg
from embodichain_core.managers.manager_base import ValidatedFunctor, ManagerBase

#: Observation groups the env itself fills (``robot``: joint state; ``sensor``: sensor data).
OBSERVATION_GROUPS = ("robot", "sensor")


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
    modes = ("add", "modify")

    @classmethod
    def check_entry(cls, checked: ValidatedFunctor, env_cfg: Any, warn: bool) -> None:
        """A known ``mode`` and a ``name`` (``a/b/c``, no empty level)."""
        cls.check_mode(checked.cfg.mode, checked.path)
        name = checked.cfg.name  # not ``is MISSING``: a deep-copied config holds a copy of the sentinel
        if not isinstance(name, str) or not name.strip() or any(not part for part in name.split("/")):
            raise ConfigError(
                join_path(checked.path, "name"),
                f"an observation functor needs a 'name' such as 'object/cube_pose', got {describe(name)}",
            )

    @classmethod
    def check_entries(cls, checked: dict[str, ValidatedFunctor], path: str) -> None:
        """An ``add`` observation must not replace a whole group: a built-in one (``robot``,
        ``sensor``) or a group other observations are added under (``object`` when another
        entry adds ``object/cube_pose``)."""
        added = {key: c.cfg.name for key, c in checked.items() if c.cfg.mode == "add"}
        for entry, obs_name in added.items():
            inner = sorted(other for key, other in added.items() if key != entry and other.startswith(obs_name + "/"))
            if obs_name in OBSERVATION_GROUPS or inner:
                users = f" (it holds {', '.join(map(repr, inner))})" if inner else " (filled by the env)"
                raise ConfigError(
                    join_path(path, entry, "name"),
                    f"observation name {obs_name!r} is an observation group{users}; adding it would replace the "
                    f"whole group. Name a member instead, e.g. '{obs_name}/<name>'",
                )

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
