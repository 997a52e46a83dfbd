"""ContactSensor: forces while a cube rests on the table, none once lifted; filters
by rigid objects and articulation links; fixed K; validation."""

from __future__ import annotations

import pytest
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import ArticulationCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_sensors.cfg import ArticulationContactFilterCfg, ContactSensorCfg

from sensors_helpers import TABLE_POS, add_sensor, make_scene

K = 8
ON_TABLE = (TABLE_POS[0], TABLE_POS[1], 0.4 + 0.025)
BLOCK = """<mujoco><worldbody><body name="block"><geom type="box" size="0.03 0.03 0.03" mass="0.5"/>
  <body name="lid" pos="0 0 0.04"><geom type="box" size="0.02 0.02 0.01" mass="0.1"/></body></body></worldbody></mujoco>"""


def settle(scene, steps: int = 60) -> None:
    for _ in range(steps):
        scene.sim.step(1)


def cube_on_table(scene) -> None:
    pose = torch.tensor([[*ON_TABLE, 1.0, 0.0, 0.0, 0.0]]).repeat(scene.num_envs, 1)
    scene["cube"].set_local_pose(pose)


def test_forces_while_resting_and_none_when_lifted():
    cfg = ContactSensorCfg(uid="touch", rigid_uid_list=["cube", "table"], max_contacts_per_env=K)
    scene, (sensor,) = make_scene(cfg, num_envs=2, cube_dynamic=True)
    cube_on_table(scene)
    settle(scene)
    sensor.update()
    data = sensor.get_data()
    assert {k: tuple(v.shape) for k, v in data.items()} == {
        "position": (2, K, 3),
        "normal": (2, K, 3),
        "force": (2, K, 3),
        "friction": (2, K, 3),
        "impulse": (2, K),
        "distance": (2, K),
        "user_ids": (2, K, 2),
        "is_valid": (2, K),
    }
    assert data["is_valid"].dtype == torch.bool
    assert data["user_ids"].dtype == torch.int32
    valid = data["is_valid"]
    assert valid.sum(dim=1).min() >= 1
    total = (data["force"] * valid[..., None]).sum(dim=1)  # on the cube (side 0), newtons
    mass = float(scene.model.body_mass[scene["cube"].body_id])
    assert torch.allclose(total, torch.tensor([0.0, 0.0, 9.81 * mass]).expand(2, 3), atol=0.05 * 9.81 * mass)
    first = data["user_ids"][0, 0].tolist()
    assert sensor.actor_name(first[0]) == "cube"
    assert sensor.uid_of_actor(first[1]) == "table"
    assert torch.allclose(data["normal"][valid], torch.tensor([0.0, 0.0, 1.0]), atol=1e-6)
    assert (data["impulse"][valid] > 0).all()
    assert (data["force"][~valid] == 0).all()
    # lift the cube: contacts vanish
    pose = scene["cube"].get_local_pose()
    pose[:, 2] += 0.5
    scene["cube"].set_local_pose(pose)
    scene.sim.forward()
    sensor.update()
    assert not sensor.get_data()["is_valid"].any()
    assert sensor.get_data()["force"].abs().sum() == 0


def test_filters_need_both_or_either_and_fixed_k():
    both = ContactSensorCfg(uid="both", rigid_uid_list=["cube"], filter_need_both_actor=True)
    either = ContactSensorCfg(
        uid="either", rigid_uid_list=["cube"], filter_need_both_actor=False, max_contacts_per_env=2
    )
    everything = ContactSensorCfg(uid="all")
    scene, sensors = make_scene(both, either, everything, cube_dynamic=True)
    cube_on_table(scene)
    settle(scene)
    for s in sensors:
        s.update()
    b, e, a = (s.get_data()["is_valid"] for s in sensors)
    assert not b.any()  # the table is not watched
    assert e.shape == (1, 2)
    assert e.all()
    assert a.sum() >= 4


def test_articulation_link_filter():
    lid = ContactSensorCfg(
        uid="lid",
        articulation_cfg_list=[ArticulationContactFilterCfg(articulation_uid="block", link_name_list=["lid"])],
        filter_need_both_actor=False,
    )
    base = ContactSensorCfg(
        uid="base",
        articulation_cfg_list=[ArticulationContactFilterCfg(articulation_uid="block", link_name_list=["blo.*"])],
        filter_need_both_actor=False,
    )
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_articulation(ArticulationCfg(uid="block", mjcf=BLOCK, fix_base=False, init_pos=(0.0, 0.0, 0.031)))
    sensors = [add_sensor(scene, c) for c in (lid, base)]
    scene.build()
    settle(scene)
    for s in sensors:
        s.update()
    lid_data, base_data = (s.get_data() for s in sensors)
    assert not lid_data["is_valid"].any()
    valid = base_data["is_valid"][0]
    assert valid.any()
    names = {sensors[1].actor_name(i) for i in base_data["user_ids"][0][valid][:, 0].tolist()}
    assert names == {"block/block"}
    assert sensors[1].uid_of_actor(base_data["user_ids"][0, 0, 1]) == "default_plane"


def test_unknown_uids_and_bad_k():
    with pytest.raises(ConfigError, match="max_contacts_per_env"):
        ContactSensorCfg(uid="c", max_contacts_per_env=0)
    with pytest.raises(KeyError, match="Did you mean 'cube'"):
        make_scene(ContactSensorCfg(uid="c", rigid_uid_list=["cub"]))
