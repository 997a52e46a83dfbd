"""Every entity of a scene is a config object, not a plain mapping.

The gym-config loader turns a mapping into the config class its field declares. A config
subclass that redeclares a scene field with a looser type (``sensor: List[Any]``,
``robot: Any``) keeps the mappings as they are, and the build would then fail far from
the cause (``'dict' object has no attribute 'init_pos'``). :func:`check_scene_types`
names the entry, the declaration and its fix instead.

Example:
    >>> check_scene_types(cfg)  # doctest: +SKIP
    ConfigError: sensor[0]: is a plain mapping ({'sensor_type': 'Camera', ...}), not a config object: ...
"""

from __future__ import annotations

import dataclasses
from typing import Any, Iterator

from embodichain_core.config.errors import ConfigError

__all__ = ["check_scene_types", "SCENE_LISTS"]

#: The ``EmbodiedEnvCfg`` fields that hold lists of entity configs.
SCENE_LISTS = ("sensor", "background", "rigid_object", "rigid_object_group", "articulation", "articulation_cfg")


def check_scene_types(cfg: Any) -> None:
    """Raise when an entity of ``cfg`` (an ``EmbodiedEnvCfg``) is not a config object.

    Raises:
        ConfigError: at the entry's path, naming the class whose field declaration let the
            mapping through and the declaration that fixes it.
    """
    for owner, field, path, value in _entities(cfg):
        if not dataclasses.is_dataclass(value):
            raise ConfigError(path, _message(owner, field, value))


def _entities(cfg: Any) -> Iterator[tuple[Any, str, str, Any]]:
    """``(object holding the field, field, config path, value)`` of every entity."""
    yield cfg, "robot", "robot", cfg.robot
    for field in SCENE_LISTS:
        for i, value in enumerate(getattr(cfg, field, None) or ()):
            yield cfg, field, f"{field}[{i}]", value
    light = getattr(cfg, "light", None)
    if dataclasses.is_dataclass(light):
        for i, value in enumerate(getattr(light, "direct", None) or ()):
            yield light, "direct", f"light.direct[{i}]", value


def _message(owner_obj: Any, field: str, value: Any) -> str:
    kind = "a plain mapping" if isinstance(value, dict) else f"a {type(value).__name__}"
    shown = repr(value) if len(repr(value)) <= 80 else repr(value)[:77] + "..."
    head = f"is {kind} ({shown}), not a config object"
    owner, declared = _declaration(type(owner_obj), field)
    base = _declaration(owner.__mro__[1], field) if len(owner.__mro__) > 1 else (owner, "")
    if not base[1] or base[1] == declared:  # not a redeclaration: the value was put there in code
        return f"{head}; build it from its config class (`{declared}`), e.g. with from_dict"
    return (
        f"{head}: {owner.__name__} declares `{field}: {declared}`, so the loader leaves the mapping "
        f"as it is; declare `{field}: {base[1]}` as {base[0].__name__} does, or remove the "
        f"declaration from {owner.__name__} to inherit it"
    )


def _declaration(cls: type, field: str) -> tuple[type, str]:
    """The class of ``cls``'s MRO that declares ``field`` first, and its annotation as text."""
    for klass in cls.__mro__:
        annotation = vars(klass).get("__annotations__", {}).get(field)
        if annotation is not None:
            return klass, _text(annotation)
    return cls, ""


def _text(annotation: Any) -> str:
    if isinstance(annotation, str):
        return annotation
    return annotation.__name__ if isinstance(annotation, type) else repr(annotation).replace("typing.", "")
