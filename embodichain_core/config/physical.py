"""Physical values of the scene configs, checked at build with their config paths.

:func:`check_scene` walks an ``EmbodiedEnvCfg``'s robot, articulations, rigid
objects, backgrounds, groups and lights (paths in the gym-config layout:
``rigid_object[0].attrs.mass``, ``light.direct[0].intensity``); the rules are
listed in docs/configuration.md ("Validated values"). Sensor configs check
their own values when built, and may add ``check_values(path, sim_cfg)`` for what depends on
the simulation settings (a camera's renderer on the backend and device).
"""

from __future__ import annotations

from typing import Any

from embodichain_core.config.checks import check_int, check_number, check_vector, describe, is_number
from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.config.scene_types import check_scene_types

__all__ = ["check_scene", "check_pose", "check_attrs", "check_shape", "check_light", "check_drive"]

#: ``JointDrivePropertiesCfg`` fields -> (lower bound, open bound).
_DRIVE_RULES = {
    "stiffness": (0.0, False),
    "damping": (0.0, False),
    "max_effort": (0.0, False),
    "max_velocity": (0.0, True),
    "friction": (0.0, False),
    "armature": (0.0, False),
}
#: ``RigidBodyAttributesCfg`` number fields -> (low, high, low_open).
_ATTR_RULES = {
    "density": (0.0, None, True),
    "angular_damping": (0.0, None, False),
    "linear_damping": (0.0, None, False),
    "max_depenetration_velocity": (0.0, None, True),
    "sleep_threshold": (0.0, None, False),
    "max_linear_velocity": (0.0, None, True),
    "max_angular_velocity": (0.0, None, True),
    "contact_offset": (0.0, None, False),
    "rest_offset": (None, None, False),
    "restitution": (0.0, 1.0, False),
    "dynamic_friction": (0.0, None, False),
    "static_friction": (0.0, None, False),
}
#: ``LightCfg`` number fields -> (low, high, low_open).
_LIGHT_RULES = {
    "intensity": (0.0, None, False),
    "radius": (0.0, None, False),
    "angular_radius": (0.0, None, False),
    "halo_size": (0.0, None, False),
    "halo_falloff": (0.0, None, False),
    "spot_angle_inner": (0.0, 180.0, False),
    "spot_angle_outer": (0.0, 180.0, False),
    "rect_width": (0.0, None, True),
    "rect_height": (0.0, None, True),
}
MAX_SOLVER_ITERATIONS = 10_000


def check_scene(cfg: Any) -> None:
    """Check the physical values of every entity of ``cfg`` (an ``EmbodiedEnvCfg``).

    Raises:
        ConfigError: the first bad value, with its path and the rule it breaks.
    """
    check_scene_types(cfg)
    check_articulation(cfg.robot, "robot")
    for key in ("articulation", "articulation_cfg"):
        for i, art in enumerate(getattr(cfg, key)):
            check_articulation(art, f"{key}[{i}]")
    for key in ("background", "rigid_object"):
        for i, obj in enumerate(getattr(cfg, key)):
            check_rigid_object(obj, f"{key}[{i}]")
    for i, group in enumerate(cfg.rigid_object_group):
        path = f"rigid_object_group[{i}]"
        check_int(group.max_num, join_path(path, "max_num"), low=1, high=100_000)
        for name, member in dict(group.rigid_objects).items():
            check_rigid_object(member, join_path(path, "rigid_objects", str(name)))
    for i, light in enumerate(cfg.light.direct):
        check_light(light, f"light.direct[{i}]")
    check_indirect_light(cfg.light.indirect, "light.indirect")
    for i, sensor in enumerate(cfg.sensor):
        check_pose(sensor, f"sensor[{i}]")
        hook = getattr(sensor, "check_values", None)
        if callable(hook):
            hook(f"sensor[{i}]", cfg.sim_cfg)


def check_pose(cfg: Any, path: str) -> None:
    """``init_pos`` (3 finite numbers, metres), ``init_rot`` (3 Euler angles, degrees)
    and ``init_local_pose`` (a 4x4 matrix) when set."""
    check_vector(cfg.init_pos, 3, join_path(path, "init_pos"), what="x, y, z in metres")
    check_vector(cfg.init_rot, 3, join_path(path, "init_rot"), what="Euler x, y, z in degrees")
    pose = getattr(cfg, "init_local_pose", None)
    if pose is not None:
        where = join_path(path, "init_local_pose")
        if not isinstance(pose, (list, tuple)) or len(pose) != 4:
            raise ConfigError(where, f"expected a 4x4 matrix, got {describe(pose)}")
        for r, row in enumerate(pose):
            check_vector(row, 4, f"{where}[{r}]")


def check_scale(value: Any, path: str) -> None:
    """A per-axis scale: 3 numbers > 0."""
    check_vector(value, 3, path, low=0.0, low_open=True, what="scale factors")


def check_attrs(attrs: Any, path: str) -> None:
    """``RigidBodyAttributesCfg``: mass >= 0 (0: from density), friction >= 0,
    restitution in [0, 1], damping >= 0, solver iterations >= 1, ..."""
    mass = check_number(attrs.mass, join_path(path, "mass"), low=0.0, what="kg; 0 takes the mass from density")
    for name, (low, high, low_open) in _ATTR_RULES.items():
        check_number(getattr(attrs, name), join_path(path, name), low=low, high=high, low_open=low_open)
    if mass == 0 and attrs.density <= 0:
        raise ConfigError(join_path(path, "density"), "mass is 0 (from density), so density must be > 0")
    check_iterations(attrs, path)


def check_iterations(cfg: Any, path: str) -> None:
    """``min_position_iters`` and ``min_velocity_iters``: ints >= 1."""
    for name in ("min_position_iters", "min_velocity_iters"):
        check_int(getattr(cfg, name), join_path(path, name), low=1, high=MAX_SOLVER_ITERATIONS)


def check_rigid_object(cfg: Any, path: str) -> None:
    """Pose, attributes, ``body_scale`` and shape of a ``RigidObjectCfg``."""
    check_pose(cfg, path)
    check_attrs(cfg.attrs, join_path(path, "attrs"))
    check_scale(cfg.body_scale, join_path(path, "body_scale"))
    if cfg.max_convex_hull_num is not None:
        check_int(cfg.max_convex_hull_num, join_path(path, "max_convex_hull_num"), low=1, high=4096)
    check_shape(cfg.shape, join_path(path, "shape"))


def check_shape(shape: Any, path: str) -> None:
    """Primitive sizes > 0 (a cube's ``size`` has 3), mesh settings, the visual material."""
    kind = type(shape).__name__
    if kind == "CubeCfg":
        check_vector(shape.size, 3, join_path(path, "size"), low=0.0, low_open=True, what="full extents in metres")
    for name in ("radius", "height"):
        if hasattr(shape, name) and kind != "MeshCfg":
            check_number(getattr(shape, name), join_path(path, name), low=0.0, low_open=True, what="metres")
    if kind == "SphereCfg":
        check_int(shape.resolution, join_path(path, "resolution"), low=3, high=1024)
    if kind == "MeshCfg":
        check_int(shape.max_convex_hull_num, join_path(path, "max_convex_hull_num"), low=1, high=4096)
        check_vector(shape.project_direction, 3, join_path(path, "project_direction"))
    material = getattr(shape, "visual_material", None)
    if material is not None:
        check_material(material, join_path(path, "visual_material"))


def check_material(mat: Any, path: str) -> None:
    """``base_color`` RGBA in [0, 1], ``emissive`` RGB in [0, 1], metallic/roughness in [0, 1]."""
    check_vector(mat.base_color, 4, join_path(path, "base_color"), low=0.0, high=1.0, what="RGBA")
    check_vector(mat.emissive, 3, join_path(path, "emissive"), low=0.0, high=1.0, what="RGB")
    for name in ("metallic", "roughness"):
        check_number(getattr(mat, name), join_path(path, name), low=0.0, high=1.0)
    check_number(mat.emissive_intensity, join_path(path, "emissive_intensity"), low=0.0)
    check_number(mat.ior, join_path(path, "ior"), low=1.0)


def check_articulation(cfg: Any, path: str) -> None:
    """Pose, ``body_scale``, ``init_qpos`` (finite), attributes, drives and solver iterations."""
    check_pose(cfg, path)
    check_scale(cfg.body_scale, join_path(path, "body_scale"))
    check_attrs(cfg.attrs, join_path(path, "attrs"))
    check_iterations(cfg, path)
    check_number(cfg.sleep_threshold, join_path(path, "sleep_threshold"), low=0.0)
    if cfg.init_qpos is not None:
        check_vector(cfg.init_qpos, len(cfg.init_qpos), join_path(path, "init_qpos"))
    check_drive(cfg.drive_pros, join_path(path, "drive_pros"))
    from embodichain_core.config.solver_check import check_solver_cfg

    check_solver_cfg(cfg, path)


def check_drive(drive: Any, path: str) -> None:
    """Each drive value is a number, or ``{joint regex: number}``, within its rule
    (stiffness, damping, max_effort, friction, armature >= 0; max_velocity > 0)."""
    for name, (low, low_open) in _DRIVE_RULES.items():
        value, where = getattr(drive, name), join_path(path, name)
        if isinstance(value, dict):
            if not value:
                raise ConfigError(where, "an empty {joint regex: value} mapping sets nothing; give a number")
            for key, item in value.items():
                check_number(item, join_path(where, str(key)), low=low, low_open=low_open)
        elif is_number(value) or not isinstance(value, (list, tuple)):
            check_number(value, where, low=low, low_open=low_open)
        else:
            raise ConfigError(where, f"expected a number or {{joint regex: number}}, got {describe(value)}")


def check_light(cfg: Any, path: str) -> None:
    """Pose, ``color`` RGB in [0, 1], ``intensity`` >= 0, a non-zero ``direction``, angles."""
    check_pose(cfg, path)
    check_vector(cfg.color, 3, join_path(path, "color"), low=0.0, high=1.0, what="RGB")
    direction = check_vector(cfg.direction, 3, join_path(path, "direction"))
    if not any(direction):
        raise ConfigError(join_path(path, "direction"), "must be a non-zero vector")
    for name, (low, high, low_open) in _LIGHT_RULES.items():
        check_number(getattr(cfg, name), join_path(path, name), low=low, high=high, low_open=low_open)
    if cfg.spot_angle_inner > cfg.spot_angle_outer:
        raise ConfigError(
            join_path(path, "spot_angle_inner"),
            f"must be <= spot_angle_outer ({cfg.spot_angle_outer!r}), got {cfg.spot_angle_inner!r}",
        )


def check_indirect_light(indirect: Any, path: str) -> None:
    """``{"ambient": [r, g, b], "emission_light": {"color": [...], "intensity": x}}``."""
    if indirect is None:
        return
    if not isinstance(indirect, dict):
        raise ConfigError(path, f"expected a mapping, got {describe(indirect)}")
    for key, value in indirect.items():
        where = join_path(path, str(key))
        if key == "ambient":
            check_vector(value, 3, where, low=0.0, high=1.0, what="RGB")
        elif key == "emission_light":
            if not isinstance(value, dict):
                raise ConfigError(where, f"expected a mapping with color and intensity, got {describe(value)}")
            check_vector(value.get("color", (1, 1, 1)), 3, join_path(where, "color"), low=0.0, high=1.0)
            check_number(value.get("intensity", 1.0), join_path(where, "intensity"), low=0.0)
        else:
            raise ConfigError(where, f"unknown indirect light key {key!r}. Valid: 'ambient', 'emission_light'")
