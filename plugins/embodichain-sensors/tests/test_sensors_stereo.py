"""StereoCamera: shapes of EmbodiChain's table, disparity = fx * baseline / depth (as
computed and as seen between the two images), rig geometry, the seed's eye_in_head."""

from __future__ import annotations

import pytest
import torch

from sensors_helpers import CUBE_POS, CUBE_SIZE

from embodichain_core.config.errors import ConfigError
from embodichain_sensors.cfg import StereoCameraCfg

W, H = 160, 120
FX = 220.0
BASELINE = 0.06
EYE = (CUBE_POS[0], CUBE_POS[1] + 0.02, 1.2)


def stereo_cfg(**kw) -> StereoCameraCfg:
    base = dict(
        uid="stereo",
        width=W,
        height=H,
        intrinsics=(FX, FX, 70.2, 64.9),
        left_to_right_pos=(BASELINE, 0.0, 0.0),
        enable_depth=True,
        enable_mask=True,
        enable_disparity=True,
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(eye=EYE, target=(EYE[0], EYE[1], 0.0), up=(1.0, 0.0, 0.0)),
    )
    base.update(kw)
    return StereoCameraCfg(**base)


def test_outputs_follow_the_reference_table(scene_factory):
    _, (cam,) = scene_factory(stereo_cfg(), num_envs=2)
    data = cam.get_data()
    shapes = {k: (tuple(v.shape), v.dtype) for k, v in data.items()}
    assert shapes == {
        "color": ((2, H, W, 4), torch.uint8),
        "color_right": ((2, H, W, 4), torch.uint8),
        "depth": ((2, H, W, 1), torch.float32),
        "depth_right": ((2, H, W, 1), torch.float32),
        "mask": ((2, H, W, 1), torch.int32),
        "mask_right": ((2, H, W, 1), torch.int32),
        "disparity": ((2, H, W, 1), torch.float32),
    }


def test_disparity_matches_fx_baseline_over_depth(scene_factory):
    _, (cam,) = scene_factory(stereo_cfg())
    data = cam.get_data()
    depth, disp = data["depth"][0, ..., 0], data["disparity"][0, ..., 0]
    valid = depth > 0
    assert torch.allclose(disp[valid], FX * BASELINE / depth[valid], rtol=1e-5)
    # the cube's top face (depth 1.1) shifts by fx * b / 1.1 = 12 px between the images
    z_top = EYE[2] - CUBE_SIZE
    cube = cam.mask_id_of("cube")
    centres, tops = [], []
    for key in ("", "_right"):
        top = (data["mask" + key][0, ..., 0] == cube) & ((data["depth" + key][0, ..., 0] - z_top).abs() < 1e-3)
        us = torch.nonzero(top)[:, 1].float()
        centres.append((us.min() + us.max()).item() / 2)
        tops.append(top)
    assert abs((centres[0] - centres[1]) - FX * BASELINE / z_top) <= 1.0
    assert torch.allclose(disp[tops[0]], torch.tensor(12.0), atol=1e-2)


def test_rig_geometry_and_intrinsics(scene_factory):
    cfg = stereo_cfg(intrinsics_right=(200.0, 200.0, 80.0, 60.0), left_to_right_rot=(0.0, 0.0, 0.0))
    _, (cam,) = scene_factory(cfg)
    left, right = cam.get_left_right_arena_pose()
    centre = cam.get_arena_pose()
    assert torch.allclose((left[:, :3] + right[:, :3]) / 2, centre[:, :3], atol=1e-6)
    assert torch.allclose((right[:, :3] - left[:, :3]).norm(dim=-1), torch.tensor([BASELINE]), atol=1e-6)
    # the baseline runs along the camera's +X (image right): world -y for this camera
    assert torch.allclose(right[0, :3] - left[0, :3], torch.tensor([0.0, -BASELINE, 0.0]), atol=1e-6)
    k_left, k_right = cam.get_intrinsics()
    assert k_left[0, 0, 0] == FX
    assert k_right[0, 0, 0] == 200.0
    assert k_right[0, 0, 2] == 80.0


def test_disparity_needs_depth():
    with pytest.raises(ConfigError, match="enable_depth"):
        StereoCameraCfg(uid="s", enable_disparity=True, enable_depth=False)


def test_seed_eye_in_head_on_an_eyes_link(scene_factory):
    """The seed tutorial's camera: 960x540, fx 450, 6 cm baseline, parent ``eyes``."""
    cfg = StereoCameraCfg(
        uid="eye_in_head",
        width=960,
        height=540,
        enable_mask=True,
        enable_depth=True,
        left_to_right_pos=(0.06, 0, 0),
        intrinsics=(450, 450, 480, 270),
        intrinsics_right=(450, 450, 480, 270),
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes"),
    )
    scene, (cam,) = scene_factory(cfg, robot=True)
    data = cam.get_data()
    assert data["color"].shape == (1, 540, 960, 4)
    assert data["mask_right"].shape == (1, 540, 960, 1)
    eyes = scene["arm"].get_link_pose("eyes")
    assert torch.allclose(cam.get_arena_pose()[:, :3], eyes[:, :3], atol=1e-6)
    assert scene.model.vis.global_.offwidth >= 960
    assert scene.model.vis.global_.offheight >= 540
