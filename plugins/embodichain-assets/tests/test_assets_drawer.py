"""The sliding drawer opens to its 0.2 m limit under a pull, and its handle frame is queryable."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from embodichain_assets.seed_scene import DRAWER_POS, build_seed_scene, seed_scene_cfgs

PULL_N = 10.0


def _handle_axes(scene, env: int = 0) -> np.ndarray:
    body = scene.model.body("drawer/handle_xpos").id
    return scene.sim.xmat[env, body].reshape(3, 3).numpy()


def test_handle_frame_sits_on_the_front_and_points_into_the_drawer():
    scene = build_seed_scene()
    drawer = scene["drawer"]
    assert drawer.joint_names == ["slide_rails"]
    assert {"outer_box", "inner_drawer", "handle_xpos"} <= set(drawer.link_names)
    pose = drawer.get_link_pose("handle_xpos")
    assert pose.shape == (1, 7)
    # bar centre: panel face 0.18 + 2.5 cm posts + half the bar, 0.11 up the drawer (+0.012 rails)
    np.testing.assert_allclose(pose[0, :3].numpy(), np.add(DRAWER_POS, [0.21, 0.0, 0.122]), atol=1e-5)
    np.testing.assert_allclose(_handle_axes(scene)[:, 2], [-1.0, 0.0, 0.0], atol=1e-6)  # +Z into the drawer


@pytest.mark.parametrize("num_envs", [2])
def test_pulling_the_handle_along_minus_z_opens_the_drawer_to_its_limit(num_envs):
    scene = build_seed_scene(num_envs=num_envs)
    drawer = scene["drawer"]
    assert drawer.get_qpos_limits()[0, 0].tolist() == pytest.approx([0.0, 0.2])
    before = drawer.get_link_pose("handle_xpos").clone()
    handle = scene.model.body("drawer/handle_xpos").id
    pull = -PULL_N * _handle_axes(scene)[:, 2]  # along the handle's -Z: out of the drawer
    scene.sim.xfrc_applied[0, handle, :3] = torch.as_tensor(pull)  # env 0 only
    scene.sim.step(100)
    qpos = drawer.get_qpos()[:, 0]
    assert float(qpos[0]) == pytest.approx(0.2, abs=3e-3)  # at the limit (soft constraint)
    assert abs(float(qpos[1])) < 1e-3  # env 1 was not pulled
    assert abs(float(drawer.get_qvel()[0, 0])) < 1e-3  # and it stays there
    after = drawer.get_link_pose("handle_xpos")
    np.testing.assert_allclose((after - before)[0, :3].numpy(), [float(qpos[0]), 0.0, 0.0], atol=1e-5)
    np.testing.assert_allclose(after[1].numpy(), before[1].numpy(), atol=1e-5)


def _drawer_only_scene():
    from embodichain_core.sim.cfg import SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_articulation(seed_scene_cfgs()["drawer"])
    scene.build()
    return scene


def test_set_qpos_opens_the_drawer_and_it_stays_open():
    scene = _drawer_only_scene()  # in the seed scene the falling fork would land in the open drawer
    drawer = scene["drawer"]
    drawer.set_qpos([[0.15]], target=False)
    scene.sim.forward()
    assert float(drawer.get_qpos()[0, 0]) == pytest.approx(0.15)
    assert float(drawer.get_link_pose("handle_xpos")[0, 0]) == pytest.approx(DRAWER_POS[0] + 0.21 + 0.15, abs=1e-5)
    scene.sim.step(50)  # damping and friction only: no drive pulls it back
    assert float(drawer.get_qpos()[0, 0]) == pytest.approx(0.15, abs=1e-3)
