"""The scene of an ``EmbodiedEnv`` from its config (its ``design_scene``), and config filters."""

from __future__ import annotations

import inspect
from typing import Any, Mapping, Optional

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers.manager_base import ValidatedFunctor
from embodichain_core.sim.scene import Scene


def add_config_entities(cfg: Any, scene: Scene, events: dict[str, ValidatedFunctor]) -> None:
    """Add every entity of ``cfg`` (an ``EmbodiedEnvCfg``) to ``scene``, then let the event
    functors edit the spec (``modify_scene``); the env compiles the scene afterwards.

    ``events`` is the checked events section (``check_sections``, after :func:`filter_functors`)."""
    robot = cfg.robot
    if robot.uid is None:
        robot.uid = "robot"
    scene.add_robot(robot, "robot")
    for i, light in enumerate(cfg.light.direct):
        scene.add_light(light, f"light.direct[{i}]")
    _indirect_light(scene, cfg.light.indirect)
    for i, obj in enumerate(cfg.background):
        scene.add_rigid_object(obj, f"background[{i}]", background=True)
    for i, art in enumerate(cfg.articulation):
        scene.add_articulation(art, f"articulation[{i}]")
    for i, art in enumerate(cfg.articulation_cfg):
        scene.add_articulation(art, f"articulation_cfg[{i}]")
    for i, obj in enumerate(cfg.rigid_object):
        scene.add_rigid_object(obj, f"rigid_object[{i}]")
    for i, group in enumerate(cfg.rigid_object_group):
        scene.add_rigid_object_group(group, f"rigid_object_group[{i}]")
    for i, sensor_cfg in enumerate(cfg.sensor):
        scene.add_sensor(_make_sensor(sensor_cfg, scene, f"sensor[{i}]"), f"sensor[{i}]")
    _run_scene_hooks(scene, events)


def _indirect_light(scene: Scene, indirect: Any) -> None:
    if not indirect:
        return
    if "ambient" in indirect:
        scene.builder.spec.visual.headlight.ambient = [float(v) for v in indirect["ambient"]][:3]
    if "emission_light" in indirect:
        light = indirect["emission_light"]
        color = [float(c) * float(light.get("intensity", 1.0)) / 30.0 for c in light.get("color", (1, 1, 1))]
        scene.builder.spec.visual.headlight.diffuse = [min(1.0, c) for c in color[:3]]


def _make_sensor(sensor_cfg: Any, scene: Scene, path: str) -> Any:
    from embodichain_core.plugins import AmbiguousNameError, get_sensor_classes

    name = getattr(sensor_cfg, "sensor_type", "") or type(sensor_cfg).__name__.removesuffix("Cfg")
    try:
        _, sensor_cls = get_sensor_classes(name)
    except (KeyError, AmbiguousNameError) as err:
        raise ConfigError(f"{path}.sensor_type", str(err).strip("\"'")) from None
    return sensor_cls(sensor_cfg, scene)


def _run_scene_hooks(scene: Scene, events: dict[str, ValidatedFunctor]) -> None:
    """Class functors with ``modify_scene(cfg, scene)`` edit the spec before compile."""
    for checked in events.values():
        hook = getattr(checked.func, "modify_scene", None)
        if inspect.isclass(checked.func) and callable(hook):
            hook(checked.cfg, scene)


def filter_functors(cfg: Any, functors: Mapping[str, Optional[dict[str, ValidatedFunctor]]]) -> dict:
    """The checked sections (``check_sections``) the env builds: ``events`` without the
    visual randomization when ``cfg.filter_visual_rand``; ``dataset`` ``None`` when
    ``cfg.filter_dataset_saving``."""
    out = dict(functors)
    if cfg.filter_dataset_saving:
        out["dataset"] = None
    if cfg.filter_visual_rand:
        out["events"] = {n: c for n, c in (functors["events"] or {}).items() if not is_visual_randomization(c)}
    return out


def is_visual_randomization(checked: ValidatedFunctor) -> bool:
    """A ``randomize_*`` functor of category ``randomization.visual``, as its registry
    entry says (a registered name) or as the functor declares it (``embodichain_category``,
    for a callable or an import path)."""
    from embodichain_core.plugins.hookspecs import visual_randomization

    if checked.entry is not None:
        name, category = checked.entry.name, checked.entry.meta.get("category", "")
    else:
        name = getattr(checked.func, "__name__", "")
        category = getattr(checked.func, "embodichain_category", "")
    return visual_randomization(name, category)


def resolve_active_joints(cfg: Any, robot: Any) -> list[int]:
    """Active joints: from ``control_parts`` (mimics removed), else ``active_joint_ids``,
    else every non-mimic joint."""
    if cfg.control_parts and cfg.active_joint_ids:
        raise ConfigError("control_parts", "set either control_parts or active_joint_ids, not both")
    if cfg.control_parts:
        ids: list[int] = []
        for part in cfg.control_parts:
            try:
                ids += [i for i in robot.get_joint_ids(part, remove_mimic=True) if i not in ids]
            except KeyError as err:
                raise ConfigError("control_parts", str(err).strip("\"'")) from None
        return ids
    if cfg.active_joint_ids:
        bad = [i for i in cfg.active_joint_ids if not 0 <= int(i) < robot.dof]
        if bad:
            raise ConfigError("active_joint_ids", f"joint ids {bad} out of range for {robot.dof} joints")
        return [int(i) for i in cfg.active_joint_ids]
    return robot.active_joint_ids
