"""The batched MuJoCo Warp renderer (``renderer: warp``, Warp's CPU device) against the OpenGL
renderer at the same states: depth within 1 mm, masks equal except at silhouette edges, RGB
within the documented PSNR, cameras on moving links, visual randomization, and the
``ConfigError`` of what the ray tracer cannot do. The first test compiles the render kernel
(~10 s on 2 cores, once per kernel cache)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import RenderCfg, SimulationManagerCfg
from embodichain_sensors.cfg import CameraCfg, StereoCameraCfg

from sensors_helpers import make_scene

W, H = 64, 48
INTR = (88.0, 80.0, 38.9, 17.9)  # fx != fy, off-centre principal point
EYE = (0.30, -0.20, 1.20)
#: Documented tolerances (docs/sensors.md): depth on 99% of the pixels where the masks agree,
#: 1 mm plus 0.1% of the distance (OpenGL's depth buffer quantizes far surfaces; OpenGL draws
#: capsules and cylinders as facets, the ray tracer hits the exact surface); RGB PSNR with the
#: headlight only (the ray tracer lights per pixel, OpenGL per vertex).
DEPTH_TOL_M, DEPTH_REL, MIN_PSNR_DB = 1e-3, 1e-3, 15.0
#: PushCube-v1's point light, seen from the side (measured 29 dB at 64x48).
PUSH_CUBE_PSNR_DB = 25.0


def _cam(**kw: Any) -> CameraCfg:
    ext = CameraCfg.ExtrinsicsCfg(eye=EYE, target=(EYE[0], EYE[1], 0.0), up=(1.0, 0.0, 0.0))
    base = dict(uid="cam", width=W, height=H, intrinsics=INTR, extrinsics=ext, enable_depth=True, enable_mask=True)
    return CameraCfg(**{**base, **kw})


def _render(cfg: Any, renderer: str, lamp: bool = True, **kw: Any) -> tuple[dict, Any]:
    """Images of ``cfg`` on backend warp with ``renderer``, 2 envs (``prepare(scene)`` first)."""
    prepare = kw.pop("prepare", None)
    scene, (cam,) = make_scene(
        cfg.replace(renderer=renderer), num_envs=2, sim_cfg=SimulationManagerCfg(backend="warp"), **kw
    )
    if not lamp:
        scene.sim.set_model_field("light_active", None, 0, 0)
    if prepare is not None:
        prepare(scene, cam)
    scene.sim.step(1)
    cam.update()
    data = {k: v.cpu() for k, v in cam.get_data().items()}
    cam.close()
    return data, cam


def edge_pixels(mask: np.ndarray) -> np.ndarray:
    """Pixels with a 4-neighbour of another value (a silhouette edge)."""
    edge = np.zeros(mask.shape, dtype=bool)
    diff_v, diff_u = mask[..., 1:, :] != mask[..., :-1, :], mask[..., :, 1:] != mask[..., :, :-1]
    edge[..., 1:, :] |= diff_v
    edge[..., :-1, :] |= diff_v
    edge[..., :, 1:] |= diff_u
    edge[..., :, :-1] |= diff_u
    return edge


def psnr(a: torch.Tensor, b: torch.Tensor) -> float:
    mse = ((a[..., :3].float() - b[..., :3].float()) ** 2).mean()
    return float(10 * torch.log10(255.0**2 / mse.clamp_min(1e-12)))


def assert_parity(gl: dict, rt: dict, sfx: str = "") -> int:
    """Same keys/dtypes/shapes; depth within the tolerance where both see the same object;
    mask differences only at silhouette edges. Returns the count of differing mask pixels."""
    assert {k: (v.dtype, v.shape) for k, v in gl.items()} == {k: (v.dtype, v.shape) for k, v in rt.items()}
    mask_gl, mask_rt = (d["mask" + sfx].numpy().reshape(-1, H, W) for d in (gl, rt))  # stereo: (N, H, W, 1)
    differ = mask_gl != mask_rt
    inner = differ & ~edge_pixels(mask_gl)
    pairs = sorted(set(zip(mask_gl[inner].tolist(), mask_rt[inner].tolist())))
    assert not inner.any(), f"{int(inner.sum())} mask pixels differ away from a silhouette edge: {pairs}"
    same = ~differ
    depth_gl = gl["depth" + sfx].numpy().reshape(-1, H, W)
    depth_err = np.abs(depth_gl - rt["depth" + sfx].numpy().reshape(-1, H, W))[same]
    within = depth_err <= DEPTH_TOL_M + DEPTH_REL * depth_gl[same]
    assert within.mean() >= 0.99, np.sort(depth_err)[-20:]
    return int(differ.sum())


def test_depth_masks_and_rgb_match_the_opengl_renderer() -> None:
    gl, _ = _render(_cam(), "opengl", lamp=False)
    rt, cam = _render(_cam(), "warp", lamp=False)
    assert cam.renderer_name == "warp"
    edges = assert_parity(gl, rt)
    assert edges <= 0.01 * gl["mask"].numel()
    assert rt["mask"].eq(cam.mask_id_of("cube")).any()
    assert psnr(gl["color"], rt["color"]) >= MIN_PSNR_DB
    assert (rt["color"][..., 3] == 255).all()


def test_stereo_on_a_moving_link_matches_in_every_env() -> None:
    cfg = StereoCameraCfg(
        uid="head",
        width=W,
        height=H,
        intrinsics=INTR,
        enable_depth=True,
        enable_mask=True,
        enable_disparity=True,
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes", pos=(0.0, 0.0, 0.05)),
    )

    def turn(scene: Any, cam: Any) -> None:  # env 1 looks elsewhere: the poses come from the moved link
        scene["arm"].set_qpos(torch.tensor([[0.0], [1.0]]), target=False)

    gl, _ = _render(cfg, "opengl", robot=True, prepare=turn)
    rt, _ = _render(cfg, "warp", robot=True, prepare=turn)
    for sfx in ("", "_right"):
        assert_parity(gl, rt, sfx)
    assert not torch.equal(rt["depth"][0], rt["depth"][1])  # the two envs' views differ
    assert ((gl["disparity"] - rt["disparity"]).abs() <= 0.5).float().mean() >= 0.99


def test_a_pose_set_at_run_time_is_rendered_per_env() -> None:
    def look(scene: Any, cam: Any) -> None:  # env 1 only: written into that world's camera frame
        cam.look_at((0.9, -0.6, 0.8), (0.35, -0.15, 0.05), env_ids=[1])

    gl, _ = _render(_cam(), "opengl", prepare=look)
    rt, _ = _render(_cam(), "warp", prepare=look)
    assert_parity(gl, rt)
    assert not torch.equal(rt["mask"][0], rt["mask"][1])


@pytest.mark.parametrize(
    "field, index, value",
    [("light_diffuse", (0,), (0.1, 0.1, 0.1)), ("geom_rgba", None, (1.0, 0.0, 0.0, 1.0))],
)
def test_visual_randomization_changes_both_renderers_alike(field: str, index: Any, value: tuple) -> None:
    def randomize(scene: Any, cam: Any) -> None:  # env 1 only, as the light/material functors write
        where = (scene["cube"].geom_ids[0],) if field == "geom_rgba" else index
        scene.sim.set_model_field(field, [1], where, torch.tensor(value))

    for renderer in ("opengl", "warp"):
        data, cam = _render(_cam(), renderer, prepare=randomize)
        rgb = data["color"][..., :3].float()
        if field == "light_diffuse":
            assert rgb[1].mean() < 0.9 * rgb[0].mean(), renderer  # a dimmer lamp
        else:
            cube = data["mask"] == cam.mask_id_of("cube")
            red0, red1 = (rgb[i][cube[i]] for i in (0, 1))
            assert (red1[:, 0] - red1[:, 1]).mean() > 50 > (red0[:, 0] - red0[:, 1]).abs().mean(), renderer


def test_what_the_ray_tracer_cannot_do_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="renderer 'warp' renders the worlds of sim_cfg.backend 'warp'"):
        make_scene(_cam(renderer="warp"))
    with pytest.raises(ConfigError, match="sim_cfg.render_cfg.quality.*no reflections"):
        make_scene(_cam(), sim_cfg=SimulationManagerCfg(backend="warp", render_cfg=RenderCfg(quality="high")))
    with pytest.raises(ConfigError, match="renderer.*'warp', 'opengl'"):
        _cam(renderer="vulkan")


def test_a_per_env_field_only_opengl_reads_is_refused() -> None:
    scene, (cam,) = make_scene(_cam(enable_mask=False), num_envs=2, sim_cfg=SimulationManagerCfg(backend="warp"))
    scene.sim.set_model_field("light_intensity", [1], (0,), 5.0)  # kept on the host for OpenGL
    with pytest.raises(ConfigError, match="light_intensity.*renderer: 'opengl'"):
        cam.update()


def test_a_light_entitys_intensity_renders_through_its_diffuse_colour() -> None:
    """The Light entity writes its intensity into ``light_diffuse`` too, so the ray tracer
    accepts a per-env intensity set through it (``randomize_light``) and shows it."""

    def dim_env_1(scene: Any, cam: Any) -> None:
        scene["lamp"].set_intensity([30.0, 5.0])

    data, _ = _render(_cam(enable_mask=False), "warp", prepare=dim_env_1)
    rgb = data["color"][..., :3].float()
    assert rgb[1].mean() < 0.9 * rgb[0].mean()  # env 1's lamp is dimmer


def test_push_cube_renders_alike_with_both_renderers() -> None:
    """PushCube-v1 on backend warp, 2 envs after a few steps: one camera per renderer, same pose."""
    import gymnasium as gym

    tasks = pytest.importorskip("embodichain_tasks.rl.push_cube")
    ext = CameraCfg.ExtrinsicsCfg(eye=(1.3, -0.6, 1.1), target=(0.35, 0.0, 0.45))
    cfg = tasks.PushCubeCfg()
    cfg.sim_cfg.backend = "warp"
    cfg.sensor = [_cam(uid=uid, extrinsics=ext, renderer=r) for uid, r in (("gl", "opengl"), ("rt", "warp"))]
    env = gym.make("PushCube-v1", cfg=cfg, num_envs=2, seed=0, verbose=False).unwrapped
    try:
        env.reset(seed=0)
        for _ in range(3):
            env.step(torch.zeros(env.action_space.shape))
        images = {}
        for uid in ("gl", "rt"):
            env.sensors[uid].update()
            images[uid] = {k: v.cpu() for k, v in env.sensors[uid].get_data().items()}
    finally:
        env.close()
    edges = assert_parity(images["gl"], images["rt"])
    assert edges <= 0.02 * images["gl"]["mask"].numel()
    assert images["rt"]["mask"].eq(env.sensors["rt"].mask_id_of("cube")).any()
    assert psnr(images["gl"]["color"], images["rt"]["color"]) >= PUSH_CUBE_PSNR_DB


def test_the_poses_composed_on_the_device_follow_the_link_and_later_pose_changes() -> None:
    """The Warp renderer's view poses, composed on the device, equal the host composition
    (``get_view_poses``) for both stereo views on a moving link, also after a ``look_at``
    made once the device copies of the local pose exist."""
    cfg = StereoCameraCfg(
        uid="head", width=W, height=H, intrinsics=INTR, extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes")
    )
    scene, (cam,) = make_scene(
        cfg.replace(renderer="warp"), num_envs=2, robot=True, sim_cfg=SimulationManagerCfg(backend="warp")
    )
    scene["arm"].set_qpos(torch.tensor([[0.0], [1.0]]), target=False)
    scene.sim.step(1)

    def assert_equal_poses() -> None:
        on_device, on_host = cam._device_poses(cam), cam.get_view_poses()
        assert len(on_device) == len(on_host) == 2
        for (pos, rot), (pos_h, rot_h) in zip(on_device, on_host):
            assert pos.device == scene.sim.device
            np.testing.assert_allclose(pos.cpu().numpy(), pos_h, atol=1e-5)
            np.testing.assert_allclose(rot.cpu().numpy(), rot_h, atol=1e-5)

    cam.update()
    assert_equal_poses()
    cam.look_at((0.2, 0.1, 0.3), (0.6, 0.0, -0.4), env_ids=[1])
    assert_equal_poses()
    cam.close()
