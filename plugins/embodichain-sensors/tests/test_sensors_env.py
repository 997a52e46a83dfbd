"""Sensors in an EmbodiedEnv: registered through the entry point, built from gym-config
dicts, batched under ``obs["sensor"][uid][...]`` on reset and step, closed with the env."""

from __future__ import annotations

import torch

from sensors_helpers import HEAD_ARM

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.plugins import get_sensor_classes, list_plugins
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg, SensorCfg
from embodichain_core.sim.shapes import CubeCfg
from embodichain_sensors.camera import Camera
from embodichain_sensors.cfg import CameraCfg, ContactSensorCfg, StereoCameraCfg
from embodichain_sensors.contact import ContactSensor
from embodichain_sensors.stereo import StereoCamera

SENSORS = [
    {
        "sensor_type": "Camera",
        "uid": "cam_high",
        "width": 64,
        "height": 48,
        "intrinsics": [60, 60, 31.5, 23.5],
        "enable_depth": True,
        "enable_mask": True,
        "extrinsics": {"eye": [1.0, 0.0, 1.0], "target": [0.3, 0.0, 0.0], "up": [0, 0, 1]},
    },
    {
        "sensor_type": "StereoCamera",
        "uid": "eye_in_head",
        "width": 48,
        "height": 32,
        "intrinsics": [40, 40, 24, 16],
        "left_to_right_pos": [0.06, 0, 0],
        "enable_depth": True,
        "enable_disparity": True,
        "extrinsics": {"parent": "eyes"},
    },
    {
        "sensor_type": "ContactSensor",
        "uid": "touch",
        "rigid_uid_list": ["cube"],
        "filter_need_both_actor": False,
        "max_contacts_per_env": 4,
    },
]


def make_cfg() -> EmbodiedEnvCfg:
    return EmbodiedEnvCfg(
        num_envs=2,
        seed=0,
        verbose=False,
        max_episode_steps=10,
        robot=RobotCfg(uid="arm", mjcf=HEAD_ARM, control_parts={"all": ["j1"]}),
        control_parts=["all"],
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05, 0.05, 0.05]), init_pos=(0.3, 0.0, 0.025))],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0))]),
        sensor=[SensorCfg.from_dict(s, f"sensor[{i}]") for i, s in enumerate(SENSORS)],
    )


def test_registered_through_the_entry_point():
    assert get_sensor_classes("Camera") == (CameraCfg, Camera)
    assert get_sensor_classes("StereoCamera") == (StereoCameraCfg, StereoCamera)
    assert get_sensor_classes("ContactSensor") == (ContactSensorCfg, ContactSensor)
    assert any(p.name == "embodichain-sensors" for p in list_plugins())


def test_sensor_observations_are_batched():
    cfg = make_cfg()
    assert [type(s) for s in cfg.sensor] == [CameraCfg, StereoCameraCfg, ContactSensorCfg]
    env = EmbodiedEnv(cfg)
    try:
        obs, _ = env.reset(seed=0)
        sensor = obs["sensor"]
        assert sensor["cam_high"]["color"].shape == (2, 48, 64, 4)
        assert sensor["cam_high"]["depth"].shape == (2, 48, 64)
        assert sensor["cam_high"]["mask"].shape == (2, 48, 64)
        assert sensor["eye_in_head"]["color_right"].shape == (2, 32, 48, 4)
        assert sensor["eye_in_head"]["disparity"].shape == (2, 32, 48, 1)
        assert sensor["touch"]["is_valid"].shape == (2, 4)
        space = env.single_observation_space["sensor"]
        assert space["cam_high"]["color"].shape == (48, 64, 4)
        assert space["touch"]["force"].shape == (4, 3)
        cam = env.sensors["cam_high"]
        assert cam.uid_of_mask_id(int(sensor["cam_high"]["mask"][0, 24, 32])) in {"cube", "default_plane", "arm"}
        obs, *_ = env.step(torch.zeros(env.action_space.shape))
        assert obs["sensor"]["cam_high"]["color"].shape == (2, 48, 64, 4)
        for _ in range(5):
            obs, *_ = env.step(torch.zeros(env.action_space.shape))
        assert obs["sensor"]["touch"]["is_valid"].any(dim=1).all()  # the cube rests on the floor
        assert env.get_sensor("eye_in_head").get_intrinsics()[0].shape == (2, 3, 3)
    finally:
        env.close()
    assert env.sensors["cam_high"]._renderer is None
    assert env.sensors["eye_in_head"]._renderer is None


def test_an_unknown_parent_names_the_sensor_entry_of_the_config():
    import pytest

    from embodichain_core.config.errors import ConfigError

    cfg = make_cfg()
    cfg.sensor[1].extrinsics.parent = "eyez"
    with pytest.raises(
        ConfigError, match=r"^sensor\[1\]\.extrinsics\.parent: sensor 'eye_in_head': no link, body or site named 'eyez'"
    ) as err:
        EmbodiedEnv(cfg)
    assert "'arm/eyes'" in str(err.value)  # the closest valid choice is offered
