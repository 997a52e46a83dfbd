"""Attribute and pose registration: values computed once per reset that tasks and
planners read from ``env.affordance_datas`` (or another env dict).

``prepare_extra_attr`` computes per-entity extra attributes into
``env.extra_attrs[uid][name]``; ``register_entity_attrs`` and
``register_entity_pose`` copy entity attributes and poses into the registration
dict; ``register_info_to_env`` runs both for a list of entities.
"""

from __future__ import annotations

import copy
from typing import Any, Sequence

import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.managers.manager_base import resolve_func
from embodichain_core.sim.entities.robot import Robot

from embodichain_functors._common import ParamError, env_ids_of, validated
from embodichain_functors._entities import resolve_uids as _resolve_uids
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._kinematics import default_part, eef_pose

__all__ = [
    "prepare_extra_attr",
    "register_entity_attrs",
    "register_entity_pose",
    "register_info_to_env",
    "resolve_uids",
    "resolve_dict",
    "get_pose",
]


def resolve_uids(env: Any, entity_uids: Any) -> list[str]:
    """Expand ``"all_objects"`` (rigid objects and articulations), ``"all_robots"``,
    ``"all_sensors"`` or one uid into a list of uids; a list passes through."""
    return _resolve_uids(env, entity_uids)


def resolve_dict(env: Any, data: dict) -> dict:
    """A copy of ``data`` whose keys are expanded with :func:`resolve_uids` (values deep-copied)."""
    out: dict = {}
    for key, value in data.items():
        for uid in resolve_uids(env, key):
            out[uid] = copy.deepcopy(value)
    return out


def _uid(cfg: Any) -> str:
    return cfg["uid"] if isinstance(cfg, dict) else cfg.uid


def get_pose(env: Any, entity_cfg: Any, return_name: bool = False, to_matrix: bool = True) -> Any:
    """(N, 4, 4) (or (N, 7)) pose of an entity; robots give their control part's end effector.

    With ``return_name`` returns ``(name, pose)``, the name being the uid or the part.
    """
    entity = env.scene[_uid(entity_cfg)]
    name = _uid(entity_cfg)
    if isinstance(entity, Robot):
        parts = (
            entity_cfg.get("control_parts")
            if isinstance(entity_cfg, dict)
            else getattr(entity_cfg, "control_parts", None)
        )
        part = default_part(env, entity, parts if isinstance(parts, str) else (parts or [None])[0])
        pose, name = eef_pose(entity, part), part or name
        pose = pose if to_matrix else torch.cat((pose[:, :3, 3], _quat(pose)), -1)
    elif hasattr(entity, "get_local_pose"):
        pose = entity.get_local_pose(to_matrix=to_matrix)
    else:
        pose = entity.get_arena_pose(to_matrix=to_matrix)
    return (name, pose) if return_name else pose


def _quat(mat: torch.Tensor) -> torch.Tensor:
    from embodichain_core.utils.math import matrix_to_quat as quat_from_matrix

    return quat_from_matrix(mat[:, :3, :3]).to(mat.dtype)


def _registry(env: Any, registration: str) -> dict:
    store = getattr(env, registration, None)
    if store is None:
        store = {}
        setattr(env, registration, store)
    return store


def _extra(env: Any, uid: str) -> dict:
    return getattr(env, "extra_attrs", {}).get(uid, {})


class prepare_extra_attr(CheckedFunctor):
    """Compute extra per-entity attributes into ``env.extra_attrs[uid][name]``.

    Each item of ``attrs``: ``name``; ``entity_cfg`` or ``entity_uids`` (a uid, a list,
    ``"all_objects"``, ``"all_robots"``, ``"all_sensors"``); ``mode`` ``"static"``
    (store ``value``) or ``"callable"`` (call ``func_name``: an entity method, or a
    ``"module:function"`` called as ``f(env, env_ids, entity_cfg, **func_kwargs)``)
    with ``func_kwargs``.

    Args (params):
        attrs: the attribute specs.

    Example:
        ``{"func": "prepare_extra_attr", "mode": "reset", "params": {"attrs": [{"name": "grasp_pose_object",
        "entity_uids": "fork", "mode": "static",
        "value": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.02], [0, 0, 0, 1]]}]}}``
    """

    def check(self, env: Any, attrs: Any = ()) -> None:
        name = type(self).__name__
        for k, spec in enumerate(attrs):
            if not isinstance(spec, dict) or "name" not in spec:
                raise ParamError(name, f"attrs[{k}]", "each attribute needs a 'name'")
            if spec.get("mode", "static") not in ("static", "callable"):
                raise ParamError(name, f"attrs[{k}].mode", f"must be 'static' or 'callable', got {spec.get('mode')!r}")
            for uid in self._uids(env, spec):
                if uid not in env.scene:
                    raise ParamError(name, f"attrs[{k}]", f"no entity {uid!r} in the scene")
            if spec.get("mode") == "callable" and not spec.get("func_name"):
                raise ParamError(name, f"attrs[{k}].func_name", "a callable attribute needs 'func_name'")

    @staticmethod
    def _uids(env: Any, spec: dict) -> list[str]:
        if "entity_cfg" in spec:
            return [_uid(spec["entity_cfg"])]
        return resolve_uids(env, spec.get("entity_uids", []))

    def _value(self, env: Any, env_ids: torch.Tensor, uid: str, spec: dict) -> Any:
        if spec.get("mode", "static") == "static":
            value = spec.get("value")
            return torch.as_tensor(value, dtype=torch.float32) if isinstance(value, (list, tuple)) else value
        func, kwargs = spec["func_name"], dict(spec.get("func_kwargs") or {})
        method = getattr(env.scene[uid], func, None) if ":" not in func else None
        if callable(method):
            return method(**kwargs)
        fn = resolve_func(func, "event", f"{type(self).__name__}.attrs")
        if "entity_cfg" not in spec:
            return fn(env, env_ids, env.scene[uid], **kwargs)
        entity_cfg = spec["entity_cfg"]  # nested in the params: a mapping stays one until here
        if isinstance(entity_cfg, dict):
            entity_cfg = SceneEntityCfg.from_dict(entity_cfg).resolve(env.scene)
        return fn(env, env_ids, entity_cfg, **kwargs)

    def __call__(self, env: Any, env_ids: Any, attrs: Sequence[dict]) -> None:
        ids = env_ids_of(env, env_ids)
        store = _registry(env, "extra_attrs")
        for spec in attrs:
            for uid in self._uids(env, spec):
                store.setdefault(uid, {})[spec["name"]] = self._value(env, ids, uid, spec)


def _check_attrs(
    env: Any, entity_cfg: Any, registration: str = "affordance_datas", attrs: Sequence[str] = (), prefix: bool = True
) -> None:
    if _uid(entity_cfg) not in env.scene:
        raise ParamError("register_entity_attrs", "entity_cfg", f"no entity {_uid(entity_cfg)!r} in the scene")
    if not isinstance(registration, str) or not registration.isidentifier():
        raise ParamError("register_entity_attrs", "registration", f"must be an identifier, got {registration!r}")


@validated(_check_attrs)
def register_entity_attrs(
    env: Any,
    env_ids: Any,
    entity_cfg: Any,
    registration: str = "affordance_datas",
    attrs: Sequence[str] = (),
    prefix: bool = True,
) -> None:
    """Copy entity attributes (or ``prepare_extra_attr`` values) into ``env.<registration>``.

    A prepared extra attribute wins over an entity attribute of the same name;
    callables are called without arguments. Keys are ``<uid>_<attr>`` (``<attr>``
    with ``prefix=False``).

    Args:
        env: the env.
        env_ids: unused (values cover every env).
        entity_cfg: the entity.
        registration: env dict receiving the values.
        attrs: attribute names.
        prefix: prefix keys with the uid.

    Example:
        ``{"func": "register_entity_attrs", "mode": "reset", "params": {"entity_cfg": {"uid": "fork"},
        "attrs": ["body_scale"]}}``
    """
    uid, store = _uid(entity_cfg), _registry(env, registration)
    entity, extra = env.scene[uid], _extra(env, uid)
    for attr in attrs:
        if attr in extra:
            value = extra[attr]
        elif hasattr(entity, attr):
            value = getattr(entity, attr)
            value = value() if callable(value) else value
        else:
            raise KeyError(f"register_entity_attrs: {uid!r} has no attribute or extra attribute {attr!r}")
        store[f"{uid}_{attr}" if prefix else attr] = value


def _check_pose(env: Any, entity_cfg: Any, registration: str = "affordance_datas", **_: Any) -> None:
    _check_attrs(env, entity_cfg, registration)


@validated(_check_pose)
def register_entity_pose(
    env: Any,
    env_ids: Any,
    entity_cfg: Any,
    registration: str = "affordance_datas",
    compute_relative: Any = "all_robots",
    compute_pose_object_to_arena: bool = True,
    to_matrix: bool = True,
) -> None:
    """Register an entity's pose, other poses relative to it, and its object-frame poses in the env frame.

    Keys: ``<uid>_pose`` (robots: ``<part>_pose``, the part's end effector);
    ``<other>_pose_in_<uid>`` for each uid of ``compute_relative``; and for an
    extra attribute ``<name>_pose_object`` (a pose in the object frame),
    ``<uid>_<name>_pose`` in the env frame.

    Args:
        env: the env.
        env_ids: unused (values cover every env).
        entity_cfg: the entity.
        registration: env dict receiving the values.
        compute_relative: uids (or ``"all_robots"``...) whose poses are expressed in this entity's frame.
        compute_pose_object_to_arena: convert ``*_pose_object`` extra attributes.
        to_matrix: store (N, 4, 4) (else (N, 7)) for ``<uid>_pose``.

    Example:
        ``{"func": "register_entity_pose", "mode": "reset", "params": {"entity_cfg": {"uid": "plate"},
        "compute_relative": ["fork"]}}``
    """
    uid, store = _uid(entity_cfg), _registry(env, registration)
    name, mat = get_pose(env, entity_cfg, return_name=True, to_matrix=True)
    store[f"{name}_pose"] = mat if to_matrix else get_pose(env, entity_cfg, to_matrix=False)
    inv = torch.linalg.inv(mat.double())
    for other in resolve_uids(env, compute_relative or []):
        if other != uid and other in env.scene:
            store[f"{other}_pose_in_{uid}"] = (inv @ get_pose(env, {"uid": other}).double()).float()
    if compute_pose_object_to_arena:
        for attr, value in _extra(env, uid).items():
            if attr.endswith("_pose_object"):
                local = torch.as_tensor(value, dtype=torch.float64)
                store[f"{uid}_{attr[: -len('_object')]}"] = (mat.double() @ local).float()


def _check_info(env: Any, registry: Any, registration: str = "affordance_datas", sim_update: bool = True) -> None:
    if not isinstance(registry, (list, tuple)):
        raise ParamError("register_info_to_env", "registry", "must be a list of {entity_cfg, ...} entries")
    for k, item in enumerate(registry):
        if not isinstance(item, dict) or "entity_cfg" not in item or _uid(item["entity_cfg"]) not in env.scene:
            raise ParamError("register_info_to_env", f"registry[{k}]", "needs an 'entity_cfg' naming a scene entity")


@validated(_check_info)
def register_info_to_env(
    env: Any, env_ids: Any, registry: Sequence[dict], registration: str = "affordance_datas", sim_update: bool = True
) -> None:
    """Run :func:`register_entity_attrs` and :func:`register_entity_pose` for several entities.

    Args:
        env: the env.
        env_ids: envs (forwarded).
        registry: entries ``{entity_cfg, attrs?, prefix?, pose_register_params?}``.
        registration: env dict receiving the values.
        sim_update: refresh the simulation's kinematics first.

    Example:
        ``{"func": "register_info_to_env", "mode": "reset", "params": {"registry": [{"entity_cfg":
        {"uid": "plate"}, "pose_register_params": {"compute_relative": ["fork"]}}]}}``
    """
    if sim_update:
        env.sim.forward(env_ids_of(env, env_ids))
    for item in registry:
        cfg = item["entity_cfg"]
        if item.get("attrs"):
            register_entity_attrs(env, env_ids, cfg, registration, item["attrs"], item.get("prefix", True))
        register_entity_pose(env, env_ids, cfg, registration, **dict(item.get("pose_register_params") or {}))
