"""EmbodiChain config fields that have no MuJoCo equivalent here, reported once per build.

EmbodiChain configs set PhysX and renderer fields that MuJoCo has no counterpart for. They
are accepted (so the configs load unchanged) and range-checked, but a value other than the
field's default does not change the simulation. :func:`ignored_fields` lists every such
value of an ``EmbodiedEnvCfg`` with its config path; the env warns once per build with
:func:`warn_ignored` (an :class:`IgnoredFieldWarning` naming them all). docs/configuration.md
("What each simulation field does here") has the whole table, mapped fields included.

Example:
    >>> cfg.rigid_object[0].attrs.restitution = 0.3  # doctest: +SKIP
    >>> [f.path for f in ignored_fields(cfg)]  # doctest: +SKIP
    ['rigid_object[0].attrs.restitution']
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any, Iterator, NamedTuple

from embodichain_core.config.errors import join_path

__all__ = ["IgnoredField", "IgnoredFieldWarning", "ignored_fields", "warn_ignored", "IGNORED"]

_NO_CCD = "MuJoCo has no continuous collision detection; against tunnelling lower physics_dt or raise physics_substeps"
_NO_CLAMP = "MuJoCo has no body velocity clamp; bound velocities with damping or joint drive limits"
_SLEEP = "bodies sleep only with physics_config.enable_sleep: true (MuJoCo's sleeping islands)"
_BODY = {
    "max_depenetration_velocity": "penetration is resolved by the contact's solref time constant, not capped",
    "sleep_threshold": _SLEEP,
    "max_linear_velocity": _NO_CLAMP,
    "max_angular_velocity": _NO_CLAMP,
    "enable_ccd": _NO_CCD,
    "contact_offset": "contacts start at rest_offset (MuJoCo's geom margin); there is no separate detection offset",
    "restitution": "MuJoCo contacts are inelastic (no restitution coefficient)",
    "dynamic_friction": "MuJoCo has one sliding friction coefficient: static_friction",
}
#: Fields of an articulation's ``attrs`` that its links do not take (only static_friction applies).
_LINK_ATTRS = {
    **_BODY,
    **{
        name: "an articulation's links keep the masses, damping and contacts of their model file"
        for name in ("mass", "density", "linear_damping", "angular_damping", "rest_offset", "enable_collision")
    },
}
#: (owner kind, field) -> why the value changes nothing here.
IGNORED: dict[str, dict[str, str]] = {
    "sim": {
        "gpu_id": "backend 'mujoco_batch' runs on the CPU; 'warp' takes its GPU from sim_device ('cuda:N')",
        "thread_mode": "the batch's threads are set by cpu_num",
        "arena_space": "every env is its own MuJoCo simulation; there is no shared arena to space envs in",
    },
    "render": {
        "renderer": "a camera's own 'renderer' (warp or opengl) picks how it renders; EmbodiChain's "
        "renderer names select nothing here",
        "spp": "no path tracer; quality 'high' turns on MSAA",
        "tone_mapping_enabled": "MuJoCo's renderer has no tone mapping",
        "tone_mapping_exposure": "MuJoCo's renderer has no tone mapping",
    },
    "physics": {
        "enable_ccd": _NO_CCD,
        "bounce_threshold": "MuJoCo contacts have no restitution, so no bounce threshold",
        "length_tolerance": "a PhysX scale hint; MuJoCo needs none",
        "speed_tolerance": "a PhysX scale hint; MuJoCo needs none",
    },
    "body_attrs": _BODY,
    "link_attrs": _LINK_ATTRS,
    "rigid": {
        "use_usd_properties": "USD files are not read here",
        "acd_method": "meshes are decomposed with coacd (max_convex_hull_num parts)",
        "sdf_resolution": "MuJoCo collides convex hulls, not SDFs",
    },
    "mesh": {
        "acd_method": "meshes are decomposed with coacd (max_convex_hull_num parts)",
        "sdf_resolution": "MuJoCo collides convex hulls, not SDFs",
    },
    "light": {
        "angular_radius": "MuJoCo's lights are points or directions, without an angular size",
        "halo_size": "MuJoCo draws no light halos",
        "halo_falloff": "MuJoCo draws no light halos",
        "rect_width": "MuJoCo has no area lights; a rect light is drawn as a point light",
        "rect_height": "MuJoCo has no area lights; a rect light is drawn as a point light",
        "mesh_path": "MuJoCo has no mesh lights; a mesh light is drawn as a point light",
    },
    "articulation": {
        "sleep_threshold": _SLEEP,
        "build_pk_chain": "kinematics come from the MuJoCo model; no pytorch-kinematics chain is built",
        "compute_uv": "an articulation's meshes keep the texture coordinates of their files",
        "use_usd_properties": "USD files are not read here",
        "body_scale": "an articulation is built at the size of its model file",
        "link_attrs": "per-link overrides are not applied; edit the model file",
    },
}


class IgnoredField(NamedTuple):
    """A value that changes nothing here: its config path, the value and why."""

    path: str
    value: Any
    why: str


class IgnoredFieldWarning(UserWarning):
    """Config values with no MuJoCo equivalent (one warning per env build)."""


def _field_default(owner: Any, name: str) -> Any:
    for f in dataclasses.fields(owner):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
    return dataclasses.MISSING


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    try:
        return bool(a == b)
    except Exception:  # noqa: BLE001 - arrays and odd types: compare as text
        return repr(a) == repr(b)


def _scan(obj: Any, kind: str, path: str, reference: Any = None) -> Iterator[IgnoredField]:
    """Fields of ``obj`` listed under ``kind`` that differ from ``reference``'s (default: the
    class default of ``obj``)."""
    if obj is None or not dataclasses.is_dataclass(obj):
        return
    for name, why in IGNORED[kind].items():
        if not hasattr(obj, name):
            continue
        value = getattr(obj, name)
        default = getattr(reference, name) if reference is not None else _field_default(obj, name)
        if default is not dataclasses.MISSING and not _same(value, default):
            yield IgnoredField(join_path(path, name), value, why)


def _owned_default(owner: Any, name: str) -> Any:
    """The default of ``owner``'s field ``name`` (a nested config), from ``owner``'s class."""
    value = _field_default(owner, name)
    return None if value is dataclasses.MISSING else value


def _entities(cfg: Any) -> Iterator[tuple[Any, str, str]]:
    yield cfg.robot, "robot", "articulation"
    for key in ("articulation", "articulation_cfg"):
        for i, art in enumerate(getattr(cfg, key, None) or []):
            yield art, f"{key}[{i}]", "articulation"
    for key in ("background", "rigid_object"):
        for i, obj in enumerate(getattr(cfg, key, None) or []):
            yield obj, f"{key}[{i}]", "rigid"
    for i, group in enumerate(getattr(cfg, "rigid_object_group", None) or []):
        for name, member in dict(group.rigid_objects).items():
            yield member, join_path(f"rigid_object_group[{i}]", "rigid_objects", str(name)), "rigid"


def ignored_fields(cfg: Any) -> list[IgnoredField]:
    """Every value of ``cfg`` (an ``EmbodiedEnvCfg``) that has no effect here, by config path."""
    sim = cfg.sim_cfg
    out = [
        *_scan(sim, "sim", "sim_cfg"),
        *_scan(sim.render_cfg, "render", "sim_cfg.render_cfg"),
        *_scan(sim.physics_config, "physics", "sim_cfg.physics_config"),
    ]
    for entity, path, kind in _entities(cfg):
        out += _scan(entity, kind, path)
        attrs_kind = "link_attrs" if kind == "articulation" else "body_attrs"
        out += _scan(entity.attrs, attrs_kind, join_path(path, "attrs"), _owned_default(entity, "attrs"))
        shape = getattr(entity, "shape", None)
        if type(shape).__name__ == "MeshCfg":
            out += _scan(shape, "mesh", join_path(path, "shape"))
    for i, light in enumerate(getattr(getattr(cfg, "light", None), "direct", None) or []):
        path = f"light.direct[{i}]"
        out += _scan(light, "light", path)
        if light.light_type in ("rect", "mesh"):
            why = f"MuJoCo has no {light.light_type} lights; it is drawn as a point light"
            out.append(IgnoredField(join_path(path, "light_type"), light.light_type, why))
    if sim.physics_config.enable_sleep:  # then every sleep_threshold is mapped (SceneBuilder.sleep_policy)
        out = [f for f in out if not f.path.endswith("sleep_threshold")]
    return out


def warn_ignored(cfg: Any) -> list[IgnoredField]:
    """Warn once (an :class:`IgnoredFieldWarning`) naming every ignored value of ``cfg``.

    Returns:
        The ignored values (empty: no warning).
    """
    found = ignored_fields(cfg)
    if found:
        lines = "\n".join(f"  {f.path} = {f.value!r}: {f.why}" for f in found)
        warnings.warn(
            f"{len(found)} config value(s) have no MuJoCo equivalent and change nothing here "
            f"(docs/configuration.md, 'What each simulation field does here'):\n{lines}",
            IgnoredFieldWarning,
            stacklevel=2,
        )
    return found
