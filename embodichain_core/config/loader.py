"""Load JSON/YAML gym configs (the EmbodiChain layout) into ``EmbodiedEnvCfg``.

The layout (see docs/configuration.md)::

    {"id": "MyTask-v0",                      # required: the gym task id
     "max_episodes": 2, "demo_max_attempts": 3, "num_envs": 2, "max_episode_steps": 300,
     "headless": true, "device": "cpu", "physics_dt": 0.01, "renderer": "auto", ...
     "env": {"events": {...}, "observations": {...}, "rewards": {...}, "actions": {...},
             "dataset": {...}, "extensions": {...}, "control_parts": [...],
             "seed": 0, "ignore_terminations": false, ...},   # any EmbodiedEnvCfg field
     "robot": {...}, "sensor": [...], "light": {"direct": [...], "indirect": {...}},
     "background": [...], "rigid_object": [...], "rigid_object_group": [...],
     "articulation": [...]}

Every error is a :class:`ConfigError` whose path follows this layout
(``env.events.random_light.mode``, ``rigid_object[0].shape.fpath``), with the
closest valid keys suggested for unknown ones.

Example:
    >>> task_id, cfg, extras = load_gym_config("gym_config.yaml", {"num_envs": 4})  # doctest: +SKIP
"""

from __future__ import annotations

import copy
import json
import os
from typing import Any, Mapping, Optional, Union

from embodichain_core.config.checks import check_int
from embodichain_core.config.convert import convert_value
from embodichain_core.config.errors import ConfigError, join_path, unknown_key
from embodichain_core.config.resources import MAX_NUM_ENVS
from embodichain_core.envs.cfg import EmbodiedEnvCfg
from embodichain_core.managers.cfg import FUNCTOR_CFG_TYPES, DatasetFunctorCfg, FunctorCfg
from embodichain_core.utils.configclass import _type_hints, is_configclass

__all__ = [
    "load_config_file",
    "gym_config_to_cfg",
    "load_gym_config",
    "apply_overrides",
    "resolve_relative_paths",
    "RUN_DEFAULTS",
    "SCENE_SECTIONS",
    "SIM_KEYS",
]

#: Run-level keys read by ``run-env`` (not stored in the cfg), with their defaults.
RUN_DEFAULTS: dict[str, Any] = {"id": None, "max_episodes": 1, "demo_max_attempts": 3}
#: Top-level scene sections (cfg fields of the same name).
SCENE_SECTIONS = (
    "robot",
    "sensor",
    "light",
    "background",
    "rigid_object",
    "rigid_object_group",
    "articulation",
    "articulation_cfg",
)
#: Flat top-level simulation keys -> ``sim_cfg`` field (``renderer`` -> ``render_cfg.renderer``).
SIM_KEYS: dict[str, str] = {
    "headless": "headless",
    "viewer": "viewer",
    "viewer_port": "viewer_port",
    "device": "sim_device",
    "gpu_id": "gpu_id",
    "backend": "backend",
    "arena_space": "arena_space",
    "physics_dt": "physics_dt",
    "physics_substeps": "physics_substeps",
    "physics_config": "physics_config",
    "render_cfg": "render_cfg",
    "physical_limits": "physical_limits",
}
#: Cfg fields that may be given at the top level as well as inside ``env`` (not both).
TOP_CFG_FIELDS = ("num_envs", "max_episode_steps", "sim_cfg")
_RELATIVE_PATH_KEYS = ("fpath", "folder_path", "mesh_path")
#: Keys of a functor entry: a dataset entry with one of them but no ``func`` is a recorder missing its ``func``.
_FUNCTOR_KEYS = {"mode", "params", "save_failed_episodes", "extra"}


def load_config_file(path: Union[str, os.PathLike]) -> dict:
    """Read a JSON (``.json``) or YAML (``.yaml``/``.yml``) file whose root is a mapping.

    Raises:
        ConfigError: the file is missing, unreadable, malformed or not a mapping;
            the message names the file.
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".json", ".yaml", ".yml"):
        raise ConfigError("", f"{path}: unsupported config file type {ext or '(none)'!r}; use .json, .yaml or .yml")
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as err:
        raise ConfigError("", f"cannot read config file {path}: {err.strerror or err}") from err
    data = _parse(text, ext, path)
    if not isinstance(data, dict):
        raise ConfigError("", f"{path}: the root of a gym config must be a mapping, got {type(data).__name__}")
    return data


def _parse(text: str, ext: str, path: str) -> Any:
    if ext == ".json":
        try:
            return json.loads(text)
        except json.JSONDecodeError as err:
            raise ConfigError("", f"{path}:{err.lineno}:{err.colno}: invalid JSON: {err.msg}") from err
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise ConfigError("", f"{path}: invalid YAML: {err}") from err


def resolve_relative_paths(data: dict, base_dir: Union[str, os.PathLike]) -> dict:
    """Make relative ``fpath``/``folder_path``/``mesh_path`` values of the scene sections
    absolute when that file exists next to the config (in place; returns ``data``).
    Other relative names are left for ``get_data_path`` (the data roots)."""
    base = os.path.abspath(os.fspath(base_dir))

    def walk(node: Any) -> None:
        if isinstance(node, list):
            for item in node:
                walk(item)
        elif isinstance(node, dict):
            for key, value in node.items():
                if key in _RELATIVE_PATH_KEYS and isinstance(value, str) and value and not os.path.isabs(value):
                    candidate = os.path.join(base, os.path.expanduser(value))
                    if os.path.exists(candidate):
                        node[key] = candidate + ("/" if value.endswith("/") and not candidate.endswith("/") else "")
                else:
                    walk(value)

    for section in SCENE_SECTIONS:
        walk(data.get(section))
    return data


def gym_config_to_cfg(data: Mapping[str, Any], cfg_cls: type = EmbodiedEnvCfg) -> tuple[Any, dict]:
    """Convert a gym config mapping into ``(cfg, extras)``.

    Args:
        data: the parsed config (EmbodiChain layout, see the module docstring).
        cfg_cls: the config class to fill (a task's ``EmbodiedEnvCfg`` subclass keeps
            its own defaults for what the file does not set).

    Returns:
        The cfg, and the run-level extras ``{"id", "max_episodes", "demo_max_attempts"}``.

    Raises:
        ConfigError: unknown keys, wrong types, missing required keys (with the path).
    """
    if not isinstance(data, Mapping):
        raise ConfigError("", f"a gym config must be a mapping, got {type(data).__name__}")
    hints = _type_hints(cfg_cls)
    _check_top_level(data, hints)
    cfg = cfg_cls()
    extras = {key: _run_value(key, data.get(key, default)) for key, default in RUN_DEFAULTS.items()}
    given: dict[str, str] = {}
    for key in SCENE_SECTIONS:
        if key in data:
            setattr(cfg, key, convert_value(_section_value(key, data[key]), hints[key], key))
    if "sim_cfg" in data:
        _merge_into(cfg.sim_cfg, data["sim_cfg"], "sim_cfg")
        given["sim_cfg"] = "sim_cfg"
    for key in (*SIM_KEYS, "renderer"):  # fixed order: ``renderer`` after ``render_cfg``
        if key in data:
            _set_sim_key(cfg, key, data[key], key)
    for key in ("num_envs", "max_episode_steps"):
        if key in data:
            setattr(cfg, key, convert_value(data[key], hints[key], key))
            given[key] = key
    _apply_env_section(cfg, data["env"], hints, given)
    _check_missing(cfg)
    return cfg, extras


def _check_top_level(data: Mapping[str, Any], hints: dict) -> None:
    valid = [*RUN_DEFAULTS, "env", *SCENE_SECTIONS, *SIM_KEYS, "renderer", *TOP_CFG_FIELDS]
    for key in data:
        if key in valid:
            continue
        if key in hints:
            raise ConfigError(str(key), f"{key!r} belongs inside 'env' (write it as env.{key})")
        raise unknown_key("", str(key), valid, what="top-level key")
    for key, what in (("id", "the gym task id"), ("robot", "the robot config"), ("env", "the env section")):
        if key not in data:
            raise ConfigError(key, f"missing required key {key!r} ({what})")


def _run_value(key: str, value: Any) -> Any:
    if key == "id":
        if not isinstance(value, str) or not value:
            raise ConfigError("id", f"expected a non-empty gym task id, got {value!r}")
        return value
    value = convert_value(value, int, key)
    if value < 1:
        raise ConfigError(key, f"must be >= 1, got {value}")
    return value


def _section_value(key: str, value: Any) -> Any:
    """``background`` entries default to ``body_type: "static"``."""
    if key == "background" and isinstance(value, list):
        return [{"body_type": "static", **item} if isinstance(item, dict) else item for item in value]
    return value


def _merge_into(obj: Any, value: Any, path: str) -> None:
    """Overlay a mapping onto an existing config object, field by field."""
    if not isinstance(value, Mapping):
        raise ConfigError(path, f"expected a mapping for {type(obj).__name__}, got {type(value).__name__}")
    hints = _type_hints(type(obj))
    for key, item in value.items():
        if key not in hints:
            raise unknown_key(path, str(key), hints, what=f"{type(obj).__name__} key")
        current = getattr(obj, key)
        if is_configclass(current) and isinstance(item, Mapping):
            _merge_into(current, item, join_path(path, key))
        else:
            setattr(obj, key, convert_value(item, hints[key], join_path(path, key)))


def _set_sim_key(cfg: Any, key: str, value: Any, path: str) -> None:
    """Set a flat simulation key (``headless``, ``device``, ``renderer``...) on ``sim_cfg``."""
    sim = cfg.sim_cfg
    if key == "renderer":
        sim.render_cfg.renderer = convert_value(value, str, path)
        return
    name = SIM_KEYS[key]
    current = getattr(sim, name)
    if is_configclass(current) and isinstance(value, Mapping):
        _merge_into(current, value, path)
    else:
        setattr(sim, name, convert_value(value, _type_hints(type(sim))[name], path))


def _apply_env_section(cfg: Any, env: Any, hints: dict, given: dict[str, str]) -> None:
    if not isinstance(env, Mapping):
        raise ConfigError("env", f"expected a mapping, got {type(env).__name__}")
    valid = [name for name in hints if name not in SCENE_SECTIONS]
    for key, value in env.items():
        path = join_path("env", key)
        if key in SCENE_SECTIONS:
            raise ConfigError(path, f"{key!r} is a top-level section; move it out of 'env'")
        if key not in hints:
            raise unknown_key("env", str(key), valid, what="env key")
        if key in given:
            raise ConfigError(path, f"{key!r} is also given at {given[key]}; give it once")
        if key in FUNCTOR_CFG_TYPES:
            setattr(cfg, key, _functor_section(value, FUNCTOR_CFG_TYPES[key], path))
        elif key == "sim_cfg":
            _merge_into(cfg.sim_cfg, value, path)
        else:
            setattr(cfg, key, convert_value(value, hints[key], path))


def _functor_section(value: Any, cfg_type: type[FunctorCfg], path: str) -> Optional[dict]:
    """``{name: functor mapping}`` -> ``{name: XxxCfg}``; ``None`` entries disable a functor."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise ConfigError(
            path, f"expected a mapping of functor name -> {cfg_type.__name__}, got {type(value).__name__}"
        )
    out: dict[str, Any] = {}
    for name, item in value.items():
        where = join_path(path, str(name))
        if item is None or isinstance(item, cfg_type):
            out[name] = item
        elif not isinstance(item, Mapping):
            raise ConfigError(where, f"expected a mapping with 'func', got {type(item).__name__} {item!r}")
        elif "func" not in item and cfg_type is DatasetFunctorCfg and not _FUNCTOR_KEYS & set(item):
            out[name] = copy.deepcopy(dict(item))  # plain metadata (e.g. robot_meta)
        elif "func" not in item:
            raise ConfigError(join_path(where, "func"), "missing 'func' (a registered functor name or 'module:attr')")
        else:
            out[name] = cfg_type.from_dict(dict(item), where)
    return out


def _check_missing(cfg: Any) -> None:
    """Required values still unset, reported with their JSON-layout path."""
    missing = [m.removeprefix("cfg.") for m in cfg.validate("cfg")]
    if not missing:
        return
    path = missing[0]
    head = path.split(".")[0].split("[")[0]
    if head not in SCENE_SECTIONS and head != "sim_cfg":
        path = join_path("env", path)
    raise ConfigError(path, "missing required value")


def apply_overrides(cfg: Any, extras: dict, overrides: Optional[Mapping[str, Any]]) -> None:
    """Apply flat overrides (CLI values) in place; ``None`` values are skipped.

    Keys: ``id``, ``max_episodes``, ``demo_max_attempts``, the flat simulation keys
    (``headless``, ``device``, ``renderer``, ``physics_dt``...) and any cfg field
    (``num_envs``, ``seed``, ``max_episode_steps``, ``filter_visual_rand``...). With
    ``cfg=None`` only the run-level keys are accepted.
    """
    hints = _type_hints(type(cfg)) if cfg is not None else {}
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        if key in RUN_DEFAULTS:
            extras[key] = _run_value(key, value)
        elif cfg is not None and (key in SIM_KEYS or key == "renderer"):
            _set_sim_key(cfg, key, value, key)
        elif key in hints and key not in SCENE_SECTIONS:
            setattr(cfg, key, convert_value(value, hints[key], key))
            if key == "num_envs":
                cfg.sim_cfg.num_envs = cfg.num_envs
        else:
            valid = [*RUN_DEFAULTS, *SIM_KEYS, "renderer", *(h for h in hints if h not in SCENE_SECTIONS)]
            raise unknown_key("", str(key), valid, what="override")


def load_gym_config(
    path_or_dict: Union[str, os.PathLike, Mapping[str, Any]],
    overrides: Optional[Mapping[str, Any]] = None,
    *,
    cfg_cls: type = EmbodiedEnvCfg,
) -> tuple[str, Any, dict]:
    """Load a gym config file (or mapping), apply ``overrides``, return ``(id, cfg, extras)``.

    An ``id`` override replaces (or supplies) the config's ``id``. Relative asset paths
    of a file are first looked up next to it (:func:`resolve_relative_paths`). The
    ``control_parts`` of a robot from ``fpath``/``mjcf`` are checked against its joints.
    """
    if isinstance(path_or_dict, Mapping):
        data = copy.deepcopy(dict(path_or_dict))
    else:
        data = load_config_file(path_or_dict)
        resolve_relative_paths(data, os.path.dirname(os.path.abspath(os.fspath(path_or_dict))))
    overrides = dict(overrides or {})
    if overrides.get("id") is not None:
        data["id"] = overrides["id"]
    cfg, extras = gym_config_to_cfg(data, cfg_cls)
    apply_overrides(cfg, extras, overrides)
    # the env allocates per-env counters before it validates the rest: bound the count now
    for value, path in ((cfg.num_envs, "num_envs"), (cfg.sim_cfg.num_envs, "sim_cfg.num_envs")):
        check_int(value, path, low=1, high=MAX_NUM_ENVS, hint=" (each env is a separate MuJoCo simulation)")
    from embodichain_core.config.joint_check import check_robot_joints

    check_robot_joints(cfg.robot, "robot")  # a file-based robot's joints are known now
    return extras["id"], cfg, extras
