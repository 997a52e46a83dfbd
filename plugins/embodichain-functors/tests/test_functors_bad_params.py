"""Bad params of the functors not covered by their own test files: each is a ConfigError
naming the functor and the param, at the functor's config path."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import apply, event, field

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import ActionTermCfg, EventCfg, EventManager, ObservationCfg
from embodichain_core.managers.param_rules import data_path_params
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import RigidObjectCfg, RigidObjectGroupCfg
from embodichain_core.sim.shapes import CubeCfg

import embodichain_functors.actions as actions
import embodichain_functors.events as events
import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand

EVENTS = [
    (events.drop_rigid_object_group_sequentially, {"entity_cfg": E(uid="cube")}, "entity_cfg"),
    (events.set_detached_uids_for_env_reset, {"uids": ["cube", "nothing"]}, "uids"),
    (events.register_entity_pose, {"entity_cfg": {"uid": "nothing"}}, "entity_cfg"),
    (events.register_info_to_env, {"registry": [{"attrs": ["x"]}]}, "registry[0]"),
    (rand.randomize_joint_stiffness, {"entity_cfg": E(uid="arm"), "stiffness_range": [-2, -1]}, "stiffness_range"),
    (
        rand.randomize_joint_drive,
        {"entity_cfg": E(uid="arm", joint_names=["finger_joint2"]), "stiffness_range": [1, 2]},
        "entity_cfg",
    ),
    (rand.randomize_robot_eef_pose, {"entity_cfg": E(uid="cube")}, "entity_cfg"),
    (rand.randomize_camera_extrinsics, {"entity_cfg": E(uid="cube"), "pos_range": [[0] * 3, [1] * 3]}, "entity_cfg"),
]


@pytest.mark.parametrize("func, params, param", EVENTS, ids=[f[0].__name__ for f in EVENTS])
def test_event_functions(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(func, **params)), [0])
    assert err.value.path.startswith(f"env.events.ev.params.{param}")
    assert func.__name__ in str(err.value) or err.value.path.endswith(".uid")  # unknown uids: the core says so


CLASSES = [
    (events.replace_assets_from_group, {"entity_cfg": E(uid="cube"), "folder_path": 3}, "folder_path"),
    (events.prepare_extra_attr, {"attrs": [{"name": "x", "entity_uids": "nothing"}]}, "attrs[0]"),
    (events.create_rigid_constraint, {"obj_a_cfg": E(uid="cube"), "obj_b_cfg": E(uid="ball"), "name": ""}, "name"),
    (
        rand.randomize_rigid_object_center_of_mass,
        {"entity_cfg": E(uid="point"), "com_pos_offset_range": [[0] * 3, [1] * 3]},
        "entity_cfg",
    ),
    (rand.randomize_visual_material, {"entity_cfg": E(uid="cube"), "max_textures": 0}, "max_textures"),
    (rand.set_rigid_object_group_visual_material, {"entity_cfg": E(uid="cube"), "mat_cfg": {}}, "entity_cfg"),
    (rand.set_rigid_object_visual_material, {"entity_cfg": E(uid="cube"), "mat_cfg": 3}, "mat_cfg"),
    (rand.randomize_rigid_objects_scale, {"entity_cfgs": [], "scale_factor_range": [1, 2]}, "entity_cfgs"),
    (
        rand.randomize_rigid_object_scale,
        {"entity_cfg": E(uid="cube"), "scale_factor_range": [1, 2], "mesh_scale_levels": 0},
        "mesh_scale_levels",
    ),
    (
        rand.planner_grid_cell_sampler,
        {"position_range": [[0, 0], [1, 1]], "reference_height": 0.1, "object_uid_list": ["arm"], "grid_size": [2, 2]},
        "object_uid_list",
    ),
]


@pytest.mark.parametrize("func, params, param", CLASSES, ids=[f[0].__name__ for f in CLASSES])
def test_event_classes_fail_when_built(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        build(events=event(func, **params))
    assert func.__name__ in str(err.value)
    assert f"params.{param}" in str(err.value)


OBSERVATIONS = [
    (obs.get_object_pose, {"entity_cfg": E(uid="point")}, "entity_cfg", "add"),
    (obs.get_rigid_object_velocity, {"entity_cfg": E(uid="arm")}, "entity_cfg", "add"),
    (obs.get_object_body_scale, {"entity_cfg": E(uid="arm")}, "entity_cfg", "add"),
    (obs.normalize_robot_joint_data, {"limit": "qf_limits"}, "limit", "modify"),
    (obs.normalize_robot_joint_data, {"joint_ids": [7]}, "joint_ids", "modify"),
    (obs.normalize_robot_joint_data, {"range": [1, 0]}, "range", "modify"),
    (obs.get_sensor_pose_in_robot_frame, {"entity_cfg": E(uid="cube")}, "entity_cfg", "add"),
]


@pytest.mark.parametrize(
    "func, params, param, mode", OBSERVATIONS, ids=[f"{f[0].__name__}-{f[2]}" for f in OBSERVATIONS]
)
def test_observations(build, func, params, param, mode) -> None:
    name = "robot/qpos" if mode == "modify" else "x/y"
    with pytest.raises(ConfigError) as err:
        build(observations={"o": ObservationCfg(func=func, mode=mode, name=name, params=params)})
    assert err.value.path == f"env.observations.o.params.{param}"
    assert func.__name__ in str(err.value)


def test_semantic_mask_needs_a_mask(build) -> None:
    sensors = pytest.importorskip("embodichain_sensors.cfg")
    cam = sensors.CameraCfg(uid="cam", width=16, height=12, intrinsics=(10, 10, 8, 6))
    with pytest.raises(ConfigError, match="enable_mask"):
        build(
            sensor=[cam],
            observations={
                "s": ObservationCfg(
                    func=obs.compute_semantic_mask, mode="add", name="x/s", params={"entity_cfg": E(uid="cam")}
                )
            },
        )


@pytest.mark.parametrize(
    "func, params, param",
    [(actions.QvelTerm, {"scale": "fast"}, "scale"), (actions.QfTerm, {"disable_drive": True}, "disable_drive")],
)
def test_velocity_and_effort_terms(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        build(actions={"a": ActionTermCfg(func=func, params=params)})
    assert err.value.path == "env.actions.a"
    assert f"params.{param}" in str(err.value)


def test_group_material_lands_on_every_member(build) -> None:
    group = RigidObjectGroupCfg(
        uid="blocks",
        rigid_objects={
            k: RigidObjectCfg(shape=CubeCfg(size=[0.04] * 3), init_pos=(0.3, y, 0.02))
            for k, y in (("a", -0.3), ("b", -0.4))
        },
    )
    env = build(
        rigid_object_group=[group],
        events=event(
            rand.set_rigid_object_group_visual_material,
            entity_cfg=E(uid="blocks"),
            mat_cfg={"base_color": [0.1, 0.6, 0.1, 1.0], "metallic": 0.5},
        ),
    )
    apply(env, [2])
    mats = [m.material_id for m in env.scene["blocks"].members]
    rgba, metallic = field(env, "mat_rgba")[:, mats], field(env, "mat_metallic")[:, mats]
    assert torch.allclose(rgba[2], torch.tensor([0.1, 0.6, 0.1, 1.0]).expand(2, 4).to(rgba.dtype), atol=1e-6)
    assert (metallic[2] == 0.5).all()
    assert not torch.allclose(rgba[0], rgba[2])


@pytest.mark.parametrize(
    "func, param", [(events.replace_assets_from_group, "folder_path"), (rand.randomize_visual_material, "texture_path")]
)
def test_folders_are_data_paths_checked_with_the_config(func, param) -> None:
    """The standard functors annotate their folders ``DataPath``: a missing one is an error
    when the section is validated, before any scene is built."""
    assert data_path_params(func, 2) == {param: False}
    section = {"ev": EventCfg(func=func, mode="reset", params={"entity_cfg": {"uid": "cube"}, param: "NoSuch/none"})}
    with pytest.raises(ConfigError) as err:
        EventManager.validate_section(None, section)
    assert err.value.path == f"env.events.ev.params.{param}"
    assert func.__name__ in err.value.reason
