"""The params of a functor that name scene entities, found by annotation.

A param annotated ``SceneEntityCfg`` (bare, ``Optional`` or a ``Sequence``/``List`` of it)
names entities, whatever its name; so does an unannotated (or ``Any``) one named
``entity_cfg`` or ``*_entity_cfg``. A ``{"uid": ...}`` given to such a param is checked
against the scene's uids with the config and becomes a resolved ``SceneEntityCfg`` when the
manager is built; given to any other param, a mapping is passed as it is.

Example:
    >>> def place(env, env_ids, goal: SceneEntityCfg, others: list[SceneEntityCfg]): ...
    >>> entity_params(place, 2)
    {'goal': False, 'others': True}
"""

from __future__ import annotations

import inspect
import re
from typing import Any, Iterable, Optional

from embodichain_core.config.checks import describe
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.managers.param_rules import annotated_as, functor_params, param_items
from embodichain_core.utils.suggest import did_you_mean

__all__ = ["entity_params", "check_entity_params"]

_ENTITY = re.compile(r"\bSceneEntityCfg\b")


def _entity_kind(param: inspect.Parameter) -> Optional[bool]:
    """Whether ``param`` names a sequence of entities (``False``: one entity), else ``None``."""
    annotation = param.annotation
    if annotation is param.empty or str(annotation).replace("typing.", "") in ("", "Any"):
        return False if _conventional(param.name) else None  # not saying: the naming convention decides
    return annotated_as(param, _ENTITY)


def _conventional(name: str) -> bool:
    return name == "entity_cfg" or name.endswith("_entity_cfg")


def entity_params(func: Any, min_argc: Optional[int], keys: Iterable[str] = ()) -> dict[str, bool]:
    """The params of ``func`` naming scene entities -> whether each takes a sequence of them.

    A param annotated ``SceneEntityCfg`` (bare, ``Optional`` or a ``Sequence``/``List`` of
    it) names entities; so does an unannotated (or ``Any``) one named ``entity_cfg`` or
    ``*_entity_cfg``. Without a readable signature (or for its ``**kwargs``), the given
    ``keys`` that follow that naming convention.
    """
    args = functor_params(func, min_argc)
    found = {}
    for param in args or []:
        many = None if param.kind is param.VAR_KEYWORD else _entity_kind(param)
        if many is not None:
            found[param.name] = many
    if args is None or any(p.kind is p.VAR_KEYWORD for p in args):
        named = {p.name for p in args or []}
        found.update({k: False for k in keys if k not in named and _conventional(k)})
    return found


def check_entity_params(params: dict, entities: dict[str, bool], path: str, uids: Optional[list[str]]) -> None:
    """Each entity param (see :func:`entity_params`) is ``None`` (not given), a
    ``SceneEntityCfg`` or ``{"uid": ...}`` (a list of them where it takes a sequence) naming
    a uid of ``uids`` (not checked when ``uids`` is ``None``)."""
    for key, many in entities.items():
        for at, item in param_items(params.get(key), join_path(path, key), many):
            if item is None:
                continue
            uid: Any
            if isinstance(item, SceneEntityCfg):
                uid = item.uid
            elif isinstance(item, dict):
                uid = item.get("uid")
            else:
                raise ConfigError(at, f"expected an entity such as {{'uid': 'cube'}}, got {describe(item)}")
            if not isinstance(uid, str) or not uid:
                raise ConfigError(join_path(at, "uid"), f"expected the uid of a scene entity, got {describe(uid)}")
            if uids is not None and uid not in uids:
                raise ConfigError(join_path(at, "uid"), f"no entity {uid!r} in the scene.{did_you_mean(uid, uids)}")
