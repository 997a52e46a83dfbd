"""The seed tutorial's events and observation (ModularEnv) on the asset pack, with the demo
arm in place of the W1: forks swapped per env, table textures per env, a camera sees it.
Skipped without embodichain-assets and embodichain-sensors."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import scene_cfg

from embodichain_core.managers import EventCfg, ObservationCfg, SceneEntityCfg
from embodichain_core.sim.cfg import LightCfg, RigidBodyAttributesCfg, RigidObjectCfg
from embodichain_core.sim.shapes import MeshCfg

import embodichain_functors.events as events
import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand

pytest.importorskip("embodichain_assets", reason="needs the asset pack")
sensors = pytest.importorskip("embodichain_sensors.cfg", reason="renders with embodichain-sensors")


def seed_cfg(get_data_path):
    fork, table = SceneEntityCfg(uid="fork"), SceneEntityCfg(uid="table")
    events_cfg = {
        "replace_obj": EventCfg(
            func=events.replace_assets_from_group,
            mode="reset",
            params={"entity_cfg": fork, "folder_path": get_data_path("TableWare/tableware/fork/")},
        ),
        "randomize_fork_mass": EventCfg(
            func=rand.randomize_rigid_object_mass, mode="reset", params={"entity_cfg": fork, "mass_range": (0.1, 2.0)}
        ),
        "randomize_light": EventCfg(
            func=rand.randomize_light,
            mode="interval",
            interval_step=5,
            params={
                "entity_cfg": SceneEntityCfg(uid="point"),
                "position_range": [[-0.5, -0.5, 2], [0.5, 0.5, 2]],
                "color_range": [[0.6, 0.6, 0.6], [1, 1, 1]],
                "intensity_range": [10.0, 30.0],
            },
        ),
        "randomize_table_mat": EventCfg(
            func=rand.randomize_visual_material,
            mode="interval",
            interval_step=10,
            params={
                "entity_cfg": table,
                "random_texture_prob": 0.5,
                "texture_path": get_data_path("CocoBackground/coco"),
                "base_color_range": [[0.2, 0.2, 0.2], [1.0, 1.0, 1.0]],
            },
        ),
    }
    cfg = scene_cfg(
        events=events_cfg,
        observations={
            "obj_pose": ObservationCfg(
                func=obs.get_rigid_object_pose, mode="add", name="fork_pose", params={"entity_cfg": fork}
            )
        },
    )
    cfg.light.direct = [LightCfg(uid="point", light_type="point", intensity=20.0, init_pos=(0, 0, 2))]
    cfg.background = [
        RigidObjectCfg(
            uid="table",
            shape=MeshCfg(fpath=get_data_path("CircleTableSimple/circle_table_simple.ply"), compute_uv=True),
            attrs=RigidBodyAttributesCfg(mass=10.0, static_friction=0.95, dynamic_friction=0.85),
            body_type="kinematic",
            init_pos=(0.80, 0, 0.8),
            init_rot=(0, 90, 0),
        )
    ]
    cfg.rigid_object = [
        RigidObjectCfg(
            uid="fork",
            shape=MeshCfg(fpath=get_data_path("TableWare/tableware/fork/standard_fork_scale.ply")),
            body_scale=(0.75, 0.75, 1.0),
            init_pos=(0.8, 0, 1.0),
        )
    ]
    cfg.sensor = [
        sensors.CameraCfg(
            uid="cam",
            width=64,
            height=48,
            intrinsics=(50, 50, 32, 24),
            extrinsics=sensors.CameraCfg.ExtrinsicsCfg(eye=(0.8, -0.6, 1.4), target=(0.8, 0.0, 0.85)),
        )
    ]
    return cfg


def test_seed_tutorial_events(build) -> None:
    from embodichain_core.sim.data import get_data_path

    env = build(seed_cfg(get_data_path))
    obs_, _ = env.reset(seed=3)
    assert obs_["fork_pose"].shape == (4, 4, 4)
    meshes = env.scene.current_mesh["fork"]
    assert len(set(meshes)) > 1  # 4 envs, 6 forks: each env draws its own
    masses = env.scene["fork"].get_mass()
    assert ((masses >= 0.1) & (masses <= 2.0)).all()
    assert len(set(masses.tolist())) == 4
    for _ in range(10):  # the interval events fire at steps 5 and 10
        obs_, *_ = env.step(torch.zeros(env.action_space.shape))
    light = env.scene["point"].get_position()
    assert torch.allclose(light[:, 2], torch.full((4,), 4.0))
    assert len(set(light[:, 0].tolist())) == 4
    img = obs_["sensor"]["cam"]["color"][..., :3].float()
    assert all((img[i] - img[j]).abs().mean() > 1.0 for i in range(4) for j in range(i))  # every env looks different
