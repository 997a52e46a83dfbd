"""Camera: exact intrinsics (principal point included), depth in metres, masks
that map to uids, normals/positions, mounting on links and sites, per-env lights."""

from __future__ import annotations

import gc
import math
import weakref

import mujoco
import numpy as np
import pytest
import torch

from sensors_helpers import CUBE_POS, CUBE_SIZE, cube_corners, make_scene, mask_bbox, project_opencv

from embodichain_core.config.errors import ConfigError
from embodichain_sensors import geometry as geo
from embodichain_sensors.cfg import CameraCfg

W, H = 160, 120
INTR = (220.0, 200.0, 97.3, 44.8)  # fx != fy, principal point far from the centre (79.5, 59.5)
EYE = (0.30, -0.20, 1.20)


def down_camera(**kw) -> CameraCfg:
    """Looking straight down from EYE; image up is world +x."""
    ext = CameraCfg.ExtrinsicsCfg(eye=EYE, target=(EYE[0], EYE[1], 0.0), up=(1.0, 0.0, 0.0))
    return CameraCfg(
        uid="cam", width=W, height=H, intrinsics=INTR, extrinsics=ext, enable_depth=True, enable_mask=True, **kw
    )


def test_cube_projects_where_the_intrinsics_say(scene_factory):
    _, (cam,) = scene_factory(down_camera())
    cam.update()
    data = cam.get_data()
    assert data["color"].shape == (1, H, W, 4)
    assert data["color"].dtype == torch.uint8
    assert data["depth"].shape == (1, H, W)
    assert data["depth"].dtype == torch.float32
    assert data["mask"].shape == (1, H, W)
    assert data["mask"].dtype == torch.int32
    _, rot = geo.look_at(np.array(EYE), np.array([EYE[0], EYE[1], 0.0]), np.array([1.0, 0.0, 0.0]))
    top = (CUBE_POS[0], CUBE_POS[1], CUBE_POS[2] + CUBE_SIZE / 2)
    u, v, z = project_opencv(top, EYE, rot, INTR)
    ui, vi = int(round(u)), int(round(v))
    mask, depth = data["mask"][0].numpy(), data["depth"][0].numpy()
    assert cam.uid_of_mask_id(int(mask[vi, ui])) == "cube"
    assert abs(float(depth[vi, ui]) - z) < 1e-3
    assert abs(z - (EYE[2] - top[2])) < 1e-9
    # the silhouette of the box is the hull of its projected corners: pixel centres inside it
    uv = np.array([project_opencv(c, EYE, rot, INTR)[:2] for c in cube_corners()])
    want = (
        math.ceil(uv[:, 0].min()),
        math.floor(uv[:, 0].max()),
        math.ceil(uv[:, 1].min()),
        math.floor(uv[:, 1].max()),
    )
    got = mask_bbox(mask, cam.mask_id_of("cube"))
    assert np.all(np.abs(np.array(got) - np.array(want)) <= 1), (got, want)


def test_mask_ids_and_empty_pixels(scene_factory):
    _, (cam,) = scene_factory(down_camera(far=5.0))
    cam.update()
    mask = cam.get_data()["mask"][0]
    table = cam.mask_id_table
    assert set(table.values()) >= {"cube", "table", "default_plane"}
    assert all(cam.uid_of_mask_id(i) == uid and cam.mask_id_of(uid) == i for i, uid in table.items())
    assert cam.uid_of_mask_id(-1) is None
    assert {cam.uid_of_mask_id(int(i)) for i in mask.unique()} <= {"cube", "default_plane", "table"}


def test_normal_and_position(scene_factory):
    _, (cam,) = scene_factory(down_camera(enable_normal=True, enable_position=True))
    data = cam.get_data()
    _, rot = geo.look_at(np.array(EYE), np.array([EYE[0], EYE[1], 0.0]), np.array([1.0, 0.0, 0.0]))
    u, v, z = project_opencv((CUBE_POS[0], CUBE_POS[1], CUBE_SIZE), EYE, rot, INTR)
    ui, vi = int(round(u)), int(round(v))
    normal, pos = data["normal"][0, vi, ui].numpy(), data["position"][0, vi, ui].numpy()
    assert np.allclose(normal, [0, 0, 1], atol=1e-3)  # the top face faces the camera (+Z_cam)
    fx, fy, cx, cy = INTR
    assert np.allclose(pos, [(ui - cx) / fx * z, -(vi - cy) / fy * z, -z], atol=1e-3)
    assert data["normal"].shape == data["position"].shape == (1, H, W, 3)


def test_intrinsics_and_pose_queries(scene_factory):
    _, (cam,) = scene_factory(down_camera(), num_envs=2)
    k = cam.get_intrinsics()
    assert k.shape == (2, 3, 3)
    assert torch.allclose(k[1], torch.tensor([[220.0, 0, 97.3], [0, 200.0, 44.8], [0, 0, 1]]))
    pose = cam.get_arena_pose()
    assert pose.shape == (2, 7)
    assert torch.allclose(pose[:, :3], torch.tensor([EYE, EYE], dtype=torch.float32))
    assert cam.get_arena_pose(to_matrix=True).shape == (2, 4, 4)
    cam.set_intrinsics((110.0, 100.0, 80.0, 60.0), env_ids=[1])
    assert torch.allclose(cam.get_intrinsics()[0], k[0])
    assert cam.get_intrinsics()[1, 0, 0] == 110.0
    cam.update()
    masks = cam.get_data()["mask"]
    assert (masks[0] == cam.mask_id_of("cube")).sum() > 2 * (masks[1] == cam.mask_id_of("cube")).sum()


def test_look_at_and_set_local_pose_per_env(scene_factory):
    _, (cam,) = scene_factory(down_camera(), num_envs=2)
    cam.look_at(eye=(3.0, 3.0, 3.0), target=(3.0, 3.0, 0.0), env_ids=[0])
    cam.update()
    masks = cam.get_data()["mask"]
    assert not (masks[0] == cam.mask_id_of("cube")).any()
    assert (masks[1] == cam.mask_id_of("cube")).any()
    cam.set_local_pose(torch.tensor([[*EYE, 0.0, 1.0, 0.0, 0.0]]), env_ids=[0])  # looks down, x flipped
    assert torch.allclose(cam.get_local_pose()[0, :3], torch.tensor(EYE, dtype=torch.float32))


def test_model_camera_matches_the_sensor(scene_factory):
    """The MuJoCo camera added to the model carries the same intrinsics (for viewers)."""
    scene, (cam,) = scene_factory(down_camera())
    cam.update()
    ours = cam.get_data()["mask"][0].numpy() == cam.mask_id_of("cube")
    r = mujoco.Renderer(scene.model, H, W)
    r.enable_segmentation_rendering()
    r.update_scene(scene.sim.get_data(0), cam.views[0].camera)
    seg = r.render()[..., 0]
    r.close()
    geoms = [g for g in range(scene.model.ngeom) if cam._ids.geom_to_id[g] == cam.mask_id_of("cube")]
    theirs = np.isin(seg, geoms)
    assert np.all(np.abs(np.array(mask_bbox(ours, 1)) - np.array(mask_bbox(theirs, 1))) <= 1)


def test_mounted_on_a_robot_link_and_a_site(scene_factory):
    offset = (0.0, 0.0, 0.05)
    link = CameraCfg(
        uid="head",
        width=32,
        height=24,
        intrinsics=(30, 30, 16, 12),
        extrinsics=CameraCfg.ExtrinsicsCfg(parent="eyes", pos=offset),
    )
    full = CameraCfg(uid="head2", width=32, height=24, extrinsics=CameraCfg.ExtrinsicsCfg(parent="arm/eyes"))
    site = CameraCfg(uid="tip", width=32, height=24, extrinsics=CameraCfg.ExtrinsicsCfg(parent="tip"))
    scene, (a, b, c) = scene_factory(link, full, site, robot=True, num_envs=2)
    robot = scene["arm"]
    robot.set_qpos(torch.tensor([[0.0], [1.0]]), target=False)
    body = robot.get_link_pose("eyes", to_matrix=True)
    want = body[:, :3, 3] + body[:, :3, :3] @ torch.tensor(offset, dtype=torch.float32)
    assert torch.allclose(a.get_arena_pose()[:, :3], want, atol=1e-5)
    assert torch.allclose(b.get_arena_pose()[:, :3], body[:, :3, 3], atol=1e-5)
    assert torch.allclose(c.get_arena_pose()[:, :3], body[:, :3, 3] + body[:, :3, 2] * 0.02, atol=1e-5)
    assert a.get_data()["color"].shape == (2, 24, 32, 4)


def test_unknown_parent_is_a_config_error(scene_factory):
    cfg = CameraCfg(uid="head", width=32, height=24, extrinsics=CameraCfg.ExtrinsicsCfg(parent="eye"))
    with pytest.raises(ConfigError, match="Did you mean 'arm/eyes'"):
        scene_factory(cfg, robot=True)


def test_per_env_light_colour_shows_in_that_env_only(scene_factory):
    scene, (cam,) = scene_factory(down_camera(), num_envs=2)
    cam.update()
    before = cam.get_data()["color"].clone()
    assert torch.equal(before[0], before[1])
    scene["lamp"].set_color((1.0, 0.0, 0.0), env_ids=[1])
    cam.update()
    after = cam.get_data()["color"]
    assert torch.equal(after[0], before[0])
    on_cube = cam.get_data()["mask"][1] == cam.mask_id_of("cube")
    green_before, green_after = before[1, ..., 1][on_cube].float().mean(), after[1, ..., 1][on_cube].float().mean()
    assert green_after < green_before - 10


def test_one_renderer_per_sensor_reused(scene_factory, monkeypatch):
    import embodichain_sensors.camera as camera_mod

    made = []
    real = camera_mod.SensorRenderer
    monkeypatch.setattr(camera_mod, "SensorRenderer", lambda *a, **k: made.append(1) or real(*a, **k))
    _, (cam,) = scene_factory(down_camera(), num_envs=3)
    for _ in range(3):
        cam.update()
    assert len(made) == 1
    assert cam.get_data()["color"].shape[0] == 3


def test_a_camera_dropped_unclosed_frees_only_its_own_gl_objects(scene_factory):
    """A camera dropped without close() is freed by the garbage collector, perhaps while
    another renderer is bound: that renderer stays bound, its textures, meshes and
    framebuffer intact (GL object names are per context, so freeing the dropped
    renderer's names in the bound context would delete the bound renderer's objects)."""
    _, (dropped,) = make_scene(down_camera())
    dropped.update()
    gone = weakref.ref(dropped.renderer)
    _, (cam,) = scene_factory(down_camera())
    cam.update()
    before = {k: v.clone() for k, v in cam.get_data().items()}
    rgb, _ = cam.renderer.render(color=True)
    rgb_before = rgb.copy()
    rgb[:] = 0  # the renderer's reused buffer: the next render must write it again
    del dropped
    gc.collect()
    assert gone() is None
    rgb, _ = cam.renderer.render(color=True)  # no make_current(): still bound
    assert np.array_equal(rgb, rgb_before)
    cam.update()
    for key, value in cam.get_data().items():
        assert torch.equal(value, before[key]), key


def test_config_validation():
    with pytest.raises(ConfigError, match="intrinsics"):
        CameraCfg(uid="c", intrinsics=(0, 1, 2, 3))
    for intrinsics in ((100.0, 100.0, -1.0, 24.0), (100.0, 100.0, 32.0, -0.5)):
        with pytest.raises(ConfigError, match=r"principal point .* must be >= 0") as err:
            CameraCfg(uid="c", width=64, height=48, intrinsics=intrinsics)
        assert err.value.path == "intrinsics"
    CameraCfg(uid="c", width=64, height=48, intrinsics=(100.0, 100.0, 0.0, 0.0))  # a corner is allowed
    with pytest.raises(ConfigError, match="near"):
        CameraCfg(uid="c", near=2.0, far=1.0)
    with pytest.raises(ConfigError, match="target"):
        CameraCfg.ExtrinsicsCfg(eye=(1, 0, 0))
    cfg = CameraCfg.from_dict(
        {
            "sensor_type": "Camera",
            "uid": "cam_high",
            "width": 96,
            "height": 54,
            "intrinsics": [48.8, 48.8, 48, 27],
            "extrinsics": {"eye": [1, 0, 1], "target": [0, 0, 0], "up": [0, 0, 1]},
        }
    )
    assert isinstance(cfg, CameraCfg)
    assert cfg.extrinsics.eye == (1, 0, 1)
    assert cfg.fx == 48.8


def _mount_spec(*names: str) -> "mujoco.MjSpec":
    import mujoco

    spec = mujoco.MjSpec()
    for name in names:
        spec.worldbody.add_body(name=name)
    return spec


def test_a_partial_parent_name_matches_whole_trailing_parts() -> None:
    from types import SimpleNamespace

    from embodichain_sensors.mount import resolve_mount

    spec = _mount_spec("arm/vx300s_left/gripper_link", "arm/vx300s_left/base", "drawer/gripper_link")
    records = {"arm": SimpleNamespace(kind="robot"), "drawer": SimpleNamespace(kind="articulation")}
    assert resolve_mount(spec, "vx300s_left/gripper_link", records, "s").body == "arm/vx300s_left/gripper_link"
    # several articulations end with it: the robot's is kept
    assert resolve_mount(spec, "gripper_link", records, "s").body == "arm/vx300s_left/gripper_link"
    with pytest.raises(ConfigError, match="no link, body or site named 'ripper_link'"):
        resolve_mount(spec, "ripper_link", records, "s")  # not a substring of a part


def test_an_ambiguous_partial_parent_name_is_an_error_listing_the_matches() -> None:
    from types import SimpleNamespace

    from embodichain_sensors.mount import resolve_mount

    spec = _mount_spec("aloha/vx300s_left/gripper_link", "aloha/vx300s_right/gripper_link")
    records = {"aloha": SimpleNamespace(kind="robot")}
    with pytest.raises(ConfigError) as err:
        resolve_mount(spec, "gripper_link", records, "sensor[0].extrinsics.parent")
    assert err.value.path == "sensor[0].extrinsics.parent"
    assert "'aloha/vx300s_left/gripper_link', 'aloha/vx300s_right/gripper_link'" in err.value.reason
    assert resolve_mount(spec, "vx300s_right/gripper_link", records, "s").body == "aloha/vx300s_right/gripper_link"
