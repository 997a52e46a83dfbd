"""The sensors on the warp backend (MuJoCo Warp on Warp's CPU device): with ``renderer:
opengl`` the cameras render each world on the host from ``sim.get_model(i)``/``get_data(i)``
and see what they see on mujoco_batch; the contact sensor reads MuJoCo Warp's contacts with
the right geoms. The batched Warp renderer's parity: test_sensors_warp_render.py."""

from __future__ import annotations

import torch

from embodichain_core.sim.cfg import SimulationManagerCfg
from embodichain_sensors.cfg import ContactSensorCfg

from sensors_helpers import TABLE_POS, make_scene
from test_sensors_camera import down_camera


def _run(backend: str) -> tuple[dict, dict, float, object]:
    touch = ContactSensorCfg(uid="touch", rigid_uid_list=["cube", "table"], max_contacts_per_env=8)
    scene, (cam, contact) = make_scene(
        down_camera(renderer="opengl"),
        touch,
        num_envs=2,
        cube_dynamic=True,
        sim_cfg=SimulationManagerCfg(backend=backend),
    )
    scene["cube"].set_local_pose(torch.tensor([[TABLE_POS[0], TABLE_POS[1], 0.425, 1.0, 0.0, 0.0, 0.0]]).repeat(2, 1))
    for _ in range(60):
        scene.sim.step(1)
    cam.update()
    contact.update()
    return cam.get_data(), contact.get_data(), float(scene.model.body_mass[scene["cube"].body_id]), contact


def test_camera_and_contact_sensor_work_on_warp() -> None:
    image_cpu, _, _, _ = _run("mujoco_batch")
    image, touch, mass, sensor = _run("warp")
    assert (image["mask"] == image_cpu["mask"]).float().mean() > 0.999  # same scene, same pixels
    assert torch.allclose(image["depth"], image_cpu["depth"], atol=1e-3)
    valid = touch["is_valid"]
    assert valid.sum(dim=1).min() >= 1
    total = (touch["force"] * valid[..., None]).sum(dim=1)
    assert torch.allclose(total, torch.tensor([0.0, 0.0, 9.81 * mass]).expand(2, 3), atol=0.05 * 9.81 * mass)
    assert [sensor.actor_name(int(i)) for i in touch["user_ids"][0, 0]] == ["cube", "table"]


def test_stereo_camera_renders_the_same_images_on_warp() -> None:
    from test_sensors_stereo import stereo_cfg

    images = {}
    for backend in ("mujoco_batch", "warp"):
        scene, (cam,) = make_scene(
            stereo_cfg(renderer="opengl"), num_envs=2, sim_cfg=SimulationManagerCfg(backend=backend)
        )
        scene.sim.step(1)
        cam.update()
        images[backend] = cam.get_data()
    assert set(images["warp"]) == set(images["mujoco_batch"])
    for key, image in images["warp"].items():
        assert torch.allclose(image.float(), images["mujoco_batch"][key].float(), atol=1e-3), key
