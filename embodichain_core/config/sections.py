"""Manager sections of an env config, checked before the scene is built.

Each functor entry needs a ``func`` and a params mapping; modes are checked
against their section (events: ``startup``, ``reset``, ``interval`` and declared
custom modes); params follow the naming rules of
:mod:`embodichain_core.managers.param_rules`.
"""

from __future__ import annotations

import warnings
from typing import Any, Iterable, Optional

from embodichain_core.config.checks import check_int, check_number, describe
from embodichain_core.config.errors import ConfigError, join_path

__all__ = [
    "EVENT_MODES",
    "SECTION_MODES",
    "OBSERVATION_GROUPS",
    "check_sections",
    "check_event_mode",
    "check_observation_groups",
    "close_modes",
    "MAX_INTERVAL_STEP",
]

#: The event modes the env itself runs.
EVENT_MODES = ("startup", "reset", "interval")
#: Modes of the other manager sections.
SECTION_MODES = {
    "observations": ("add", "modify"),
    "rewards": ("add", "replace"),
    "actions": ("pre", "post"),
    "dataset": ("save",),
}
#: Largest ``interval_step`` accepted (an interval event fires every that many env steps).
MAX_INTERVAL_STEP = 10_000_000


def _distance(a: str, b: str) -> int:
    """Edit distance with adjacent transpositions counting 1 (optimal string alignment)."""
    prev2, prev = None, list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        row = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = a[i - 1] != b[j - 1]
            row[j] = min(prev[j] + 1, row[j - 1] + 1, prev[j - 1] + cost)
            if prev2 is not None and i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                row[j] = min(row[j], prev2[j - 2] + 1)
        prev2, prev = prev, row
    return prev[len(b)]


def close_modes(mode: str, choices: Iterable[str]) -> list[str]:
    """Choices ``mode`` looks like a typo of: equal up to case and spaces, or within
    one edit (two for names of 8 letters or more)."""
    norm = mode.strip().lower()
    out = []
    for choice in choices:
        limit = 2 if len(choice) >= 8 else 1
        if norm == choice.lower() or _distance(norm, choice.lower()) <= limit:
            out.append(choice)
    return out


def check_event_mode(mode: Any, path: str, declared: Iterable[str] = (), warn: bool = True) -> None:
    """Check an event's ``mode`` (``path`` is the entry's path).

    ``startup``/``reset``/``interval`` and declared custom modes (``env.custom_event_modes``
    or a functor's ``event_modes``) are accepted; any other mode is an error, with a
    suggestion when it looks like a typo of a known one (an undeclared mode would never
    fire on its own). ``warn`` is kept for callers of the earlier signature.
    """
    where = join_path(path, "mode")
    if not isinstance(mode, str) or not mode.strip():
        raise ConfigError(
            where,
            f"expected an event mode ('startup', 'reset', 'interval' or a declared custom mode), got {describe(mode)}",
        )
    declared = [str(m) for m in declared]
    known = [*EVENT_MODES, *declared]
    if mode in known:
        return
    near = close_modes(mode, known)
    if near:
        suggestion = " or ".join(repr(m) for m in near)
        raise ConfigError(
            where,
            f"unknown event mode {mode!r}. Did you mean {suggestion}? (a custom mode "
            f"with this name must be declared in env.custom_event_modes)",
        )
    raise ConfigError(
        where,
        f"unknown event mode {mode!r}: not one of {', '.join(repr(m) for m in known)}. A custom mode "
        f"(run by task code with env.event_manager.apply({mode!r}, env_ids)) must be declared in "
        "env.custom_event_modes",
    )


def check_declared_modes(modes: Any, path: str = "env.custom_event_modes") -> list[str]:
    """``custom_event_modes``: a list of non-empty names, none of them a built-in mode."""
    if modes is None:
        return []
    if isinstance(modes, (str, dict)) or not isinstance(modes, (list, tuple)):
        raise ConfigError(path, f"expected a list of mode names, got {describe(modes)}")
    for i, mode in enumerate(modes):
        if not isinstance(mode, str) or not mode.strip():
            raise ConfigError(f"{path}[{i}]", f"expected a mode name, got {describe(mode)}")
        if mode in EVENT_MODES:
            raise ConfigError(f"{path}[{i}]", f"{mode!r} is a built-in event mode; list only custom ones")
    return list(modes)


def check_sections(cfg: Any) -> None:
    """Check every functor entry of the manager sections of ``cfg`` (an ``EmbodiedEnvCfg``):
    ``func`` resolves, params match the functor's signature (names, simple types) and
    the naming rules, entity uids exist in the config, asset paths exist, modes are known."""
    from embodichain_core.managers.cfg import FUNCTOR_CFG_TYPES
    from embodichain_core.managers.manager_base import iter_section

    declared = check_declared_modes(getattr(cfg, "custom_event_modes", None))
    uids = scene_uids(cfg)
    for section, cfg_type in FUNCTOR_CFG_TYPES.items():
        path = join_path("env", section)
        for name, fcfg in iter_section(getattr(cfg, section, None), cfg_type, path):
            where = join_path(path, name)
            _check_func(fcfg, where)
            func = _check_params(section, fcfg, where)
            check_entity_refs(fcfg.params, join_path(where, "params"), uids)
            if section == "events":
                modes = [*declared, *getattr(func, "event_modes", ())]
                check_event_mode(fcfg.mode, where, modes, warn=False)
                check_interval(fcfg, where, cfg.max_episode_steps, warn=False)
            else:
                _check_section_entry(section, fcfg, where)
    check_observation_groups(cfg)


#: Observation groups the env itself fills (``robot``: joint state; ``sensor``: sensor data).
OBSERVATION_GROUPS = ("robot", "sensor")


def check_observation_groups(cfg: Any) -> None:
    """An ``add`` observation must not replace a whole group: a built-in one (``robot``,
    ``sensor``) or a group other observations are added under (``object`` when another
    entry adds ``object/cube_pose``).

    Raises:
        ConfigError: at ``env.observations.<entry>.name``, naming the group.
    """
    from embodichain_core.managers.cfg import FUNCTOR_CFG_TYPES
    from embodichain_core.managers.manager_base import iter_section

    path = join_path("env", "observations")
    entries = list(iter_section(getattr(cfg, "observations", None), FUNCTOR_CFG_TYPES["observations"], path))
    added = {name: fcfg.name for name, fcfg in entries if fcfg.mode == "add" and isinstance(fcfg.name, str)}
    for entry, obs_name in added.items():
        inner = sorted(other for key, other in added.items() if key != entry and other.startswith(obs_name + "/"))
        if obs_name in OBSERVATION_GROUPS or inner:
            users = f" (it holds {', '.join(map(repr, inner))})" if inner else " (filled by the env)"
            raise ConfigError(
                join_path(path, entry, "name"),
                f"observation name {obs_name!r} is an observation group{users}; adding it would replace the "
                f"whole group. Name a member instead, e.g. '{obs_name}/<name>'",
            )


#: Positional arguments before the params, per section (as the managers call functors).
_MIN_ARGC = {"events": 2, "observations": 2, "rewards": 4, "dataset": 2}
_KINDS = {
    "events": "event",
    "observations": "observation",
    "rewards": "reward",
    "actions": "action",
    "dataset": "dataset",
}
#: Params naming asset data (``get_data_path`` names or paths) that must exist.
DATA_PATH_PARAMS = ("folder_path", "texture_path")


def _check_params(section: str, fcfg: Any, where: str) -> Any:
    """Resolve ``func``; check the params against its signature and the naming rules."""
    from embodichain_core.managers.manager_base import check_params, resolve_func
    from embodichain_core.managers.param_rules import check_named_params, check_param_types

    func = resolve_func(fcfg.func, _KINDS[section], where)
    if not isinstance(fcfg.params, dict):
        raise ConfigError(join_path(where, "params"), f"expected a mapping of params, got {describe(fcfg.params)}")
    if section in _MIN_ARGC:  # action terms take their params in their constructor
        check_params(func, fcfg.params, _MIN_ARGC[section], where)
        check_param_types(func, fcfg.params, where, _MIN_ARGC[section])
    check_named_params(fcfg.params, where, _func_name(func))
    for key in DATA_PATH_PARAMS:
        if fcfg.params.get(key) is not None:
            check_data_path(fcfg.params[key], join_path(where, "params", key), _func_name(func))
    return func


def check_data_path(value: Any, path: str, functor: str = "") -> None:
    """An asset name or path that ``get_data_path`` resolves (a glob pattern is left to
    its functor)."""
    from embodichain_core.sim.data import get_data_path

    lead = f"functor {functor!r}: " if functor else ""
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(path, f"{lead}expected an asset name or path, got {describe(value)}")
    if any(char in value for char in "*?["):
        return
    try:
        get_data_path(value)
    except FileNotFoundError as err:
        raise ConfigError(path, lead + str(err).strip("\"'")) from None


def scene_uids(cfg: Any) -> list[str]:
    """Every uid the config's scene will have (the ground plane included); uids must be
    unique, non-empty and free of ``/`` (group members are named ``<group>/<member>``)."""
    from embodichain_core.sim.scene_build.builder import GROUND_UID

    entries = [("robot", getattr(cfg.robot, "uid", None) or "robot")]
    for key in ("articulation", "articulation_cfg", "background", "rigid_object", "rigid_object_group", "sensor"):
        entries += [(f"{key}[{i}]", obj.uid) for i, obj in enumerate(getattr(cfg, key))]
    entries += [(f"light.direct[{i}]", light.uid) for i, light in enumerate(cfg.light.direct)]
    seen: dict[str, str] = {GROUND_UID: "the ground plane"}
    for path, uid in entries:
        where = join_path(path, "uid")
        if not isinstance(uid, str) or not uid or "/" in uid:
            raise ConfigError(where, f"expected a non-empty uid without '/', got {describe(uid)}")
        if uid in seen:
            raise ConfigError(where, f"uid {uid!r} is already used by {seen[uid]}; uids must be unique")
        seen[uid] = path
    return list(seen)


def check_entity_refs(params: dict, path: str, uids: list[str]) -> None:
    """Entity params (``entity_cfg``, ``*_entity_cfg``, ``object_cfg``...) name a
    configured uid; a mapping needs a ``uid``; ``None`` means "not given"."""
    from embodichain_core.managers.cfg import SceneEntityCfg
    from embodichain_core.managers.manager_base import ENTITY_PARAM_KEYS
    from embodichain_core.utils.suggest import did_you_mean

    for key, value in params.items():
        if value is None or not (key in ENTITY_PARAM_KEYS or str(key).endswith("entity_cfg")):
            continue
        where = join_path(path, str(key))
        if isinstance(value, dict):
            uid = value.get("uid")
        elif isinstance(value, SceneEntityCfg):
            uid = value.uid
        else:
            raise ConfigError(where, f"expected an entity such as {{'uid': 'cube'}}, got {describe(value)}")
        if not isinstance(uid, str) or not uid:
            raise ConfigError(join_path(where, "uid"), f"expected the uid of a scene entity, got {describe(uid)}")
        if uid not in uids:
            raise ConfigError(join_path(where, "uid"), f"no entity {uid!r} in the scene.{did_you_mean(uid, uids)}")


def _func_name(func: Any) -> str:
    return func if isinstance(func, str) else getattr(func, "__name__", type(func).__name__)


def _check_func(fcfg: Any, where: str) -> None:
    from embodichain_core.utils.configclass import MISSING

    func = fcfg.func
    if func is None or isinstance(func, type(MISSING)) or (isinstance(func, str) and not func.strip()):
        raise ConfigError(join_path(where, "func"), "missing 'func' (a registered functor name or 'module:attr')")
    if not isinstance(func, str) and not callable(func):
        raise ConfigError(join_path(where, "func"), f"expected a functor name or a callable, got {describe(func)}")


def check_interval(fcfg: Any, where: str, max_episode_steps: Optional[int], warn: bool = True) -> None:
    """``interval_step``: an int in [1, MAX_INTERVAL_STEP]. A per-env ``interval`` event
    whose step is above ``max_episode_steps`` never fires (its counter restarts with each
    episode): a warning says so (a short smoke-test episode is not an error)."""
    if not isinstance(fcfg.is_global, bool):
        raise ConfigError(join_path(where, "is_global"), f"expected true/false, got {describe(fcfg.is_global)}")
    step = check_int(fcfg.interval_step, join_path(where, "interval_step"), low=1, high=MAX_INTERVAL_STEP)
    limit = max_episode_steps if isinstance(max_episode_steps, int) and max_episode_steps > 0 else None
    if warn and fcfg.mode == "interval" and limit is not None and step > limit and not fcfg.is_global:
        warnings.warn(
            f"{join_path(where, 'interval_step')}: {step} is above max_episode_steps ({limit}): the "
            f"per-env counter restarts with each episode, so this event never fires",
            stacklevel=3,
        )


def _check_section_entry(section: str, fcfg: Any, where: str) -> None:
    modes = SECTION_MODES[section]
    mode = fcfg.mode
    if mode not in modes:
        hint = close_modes(mode, modes) if isinstance(mode, str) else []
        extra = f" Did you mean {hint[0]!r}?" if hint else ""
        raise ConfigError(
            join_path(where, "mode"), f"mode must be {' or '.join(map(repr, modes))}, got {describe(mode)}.{extra}"
        )
    if section == "observations":
        name = fcfg.name
        if not isinstance(name, str) or not name.strip() or any(not part for part in name.split("/")):
            raise ConfigError(
                join_path(where, "name"),
                f"an observation functor needs a 'name' such as 'object/cube_pose', got {describe(name)}",
            )
    if section == "rewards":
        check_number(fcfg.weight, join_path(where, "weight"))
    if section == "dataset" and not isinstance(fcfg.save_failed_episodes, bool):
        raise ConfigError(
            join_path(where, "save_failed_episodes"), f"expected true/false, got {describe(fcfg.save_failed_episodes)}"
        )
