"""Visual randomization: lights, materials, textures and cameras change per env what a
camera (embodichain-sensors) sees, in the chosen envs only."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import apply, event, field, others, scene_cfg, write_png

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import LightCfg

import embodichain_functors.randomization as rand

sensors = pytest.importorskip("embodichain_sensors.cfg", reason="renders with embodichain-sensors")
IDS = [1, 2]


def camera(uid: str = "cam", **kwargs) -> object:
    """A 64x48 camera looking down at the cube and the ground around it."""
    ext = kwargs.pop("extrinsics", sensors.CameraCfg.ExtrinsicsCfg(eye=(0.5, -0.5, 0.5), target=(0.5, 0.0, 0.0)))
    return sensors.CameraCfg(
        uid=uid, width=64, height=48, intrinsics=(50.0, 50.0, 32.0, 24.0), extrinsics=ext, **kwargs
    )


def images(env) -> torch.Tensor:
    """(N, H, W, 3) float colour images of ``cam`` at the current state."""
    return env.get_obs()["sensor"]["cam"]["color"][..., :3].float()


def changed(before: torch.Tensor, after: torch.Tensor) -> list[bool]:
    return [(a - b).abs().mean().item() > 1.0 for a, b in zip(after, before)]


# -- lights ------------------------------------------------------------------------------------------
def test_light_position_colour_intensity_per_env(build) -> None:
    env = build(
        sensor=[camera()],
        events=event(
            rand.randomize_light,
            entity_cfg=E(uid="point"),
            position_range=[[-0.5, -0.5, -1.0], [0.5, 0.5, -1.0]],
            color_range=[[1.0, 0.0, 0.0], [1.0, 0.2, 0.2]],
            intensity_range=[10.0, 10.0],
        ),
    )
    light = env.scene["point"]
    before, pos0 = images(env), light.get_position()
    ids = apply(env, IDS)
    pos = light.get_position()
    assert (pos[ids, :2].abs() <= 0.5 + 1e-6).all()
    assert torch.allclose(pos[ids, 2], torch.ones(2))
    assert torch.equal(pos[others(IDS)], pos0[others(IDS)])
    assert torch.allclose(light.get_intensity()[ids], torch.full((2,), 30.0))
    assert (light.get_color()[ids, 0] == 1).all()
    assert (light.get_color()[others(IDS)] == 1).all()
    # the light_pos0 we write is what mj_setConst derives (so skipping it is exact)
    pos0_field = field(env, "light_pos0").clone()
    env.sim.batch.set_const(None)
    assert torch.allclose(field(env, "light_pos0"), pos0_field)
    after = images(env)
    assert changed(before, after) == [i in IDS for i in range(4)]
    redness = (after[..., 0] - after[..., 2]).mean(dim=(1, 2))
    assert redness[ids].min() > redness[others(IDS)].max()


def test_sun_light_draws_one_value_and_ignores_position(build) -> None:
    cfg = scene_cfg()
    cfg.light.direct = [LightCfg(uid="sun", light_type="sun", direction=(0.0, 0.0, -1.0), init_pos=(0, 0, 3))]
    cfg.events = event(
        rand.randomize_light,
        entity_cfg=E(uid="sun"),
        position_range=[[1, 1, 1], [2, 2, 2]],
        direction_range=[[-0.3, -0.3, 0.0], [0.3, 0.3, 0.0]],
        color_range=[[0.2] * 3, [1.0] * 3],
    )
    env = build(cfg)
    apply(env, [1])
    direction = field(env, "light_dir")[:, env.scene["sun"].light_id]
    assert torch.allclose(direction, direction[:1].expand(4, 3))
    assert not torch.allclose(direction[0], torch.tensor([0.0, 0, -1], dtype=direction.dtype))
    assert torch.allclose(env.scene["sun"].get_position(), torch.tensor([0.0, 0, 3]).expand(4, 3))
    colour = env.scene["sun"].get_color()
    assert torch.allclose(colour, colour[:1].expand(4, 3))


def test_point_light_ignores_direction_range(build) -> None:
    env = build(events=event(rand.randomize_light, entity_cfg=E(uid="point"), direction_range=[[1, 1, 1], [2, 2, 2]]))
    before = field(env, "light_dir")
    apply(env, IDS)
    assert torch.equal(field(env, "light_dir"), before)


# -- materials ------------------------------------------------------------------------------------------
def test_base_colour_of_the_ground_is_seen_per_env(build) -> None:
    env = build(
        sensor=[camera()],
        events=event(
            rand.randomize_visual_material,
            entity_cfg=E(uid="default_plane"),
            base_color_range=[[0.9, 0.0, 0.0], [1.0, 0.1, 0.1]],
            random_texture_prob=0.0,
        ),
    )
    before = images(env)
    ids = apply(env, IDS)
    mat = env.scene.model.geom_matid[0]
    rgba = field(env, "mat_rgba")[:, mat]
    assert (rgba[ids, 0] >= 0.9).all()
    assert (rgba[ids, 1] <= 0.1).all()
    assert (field(env, "mat_texid")[ids, mat, 1] == -1).all()  # a solid colour replaces the checker
    after = images(env)
    assert changed(before, after) == [i in IDS for i in range(4)]
    redness = (after[..., 0] - after[..., 1]).mean(dim=(1, 2))
    assert redness[ids].min() > 40
    assert redness[others(IDS)].max() < 10


def test_random_textures_from_a_folder(build, tmp_path) -> None:
    write_png(str(tmp_path / "red.png"), (255, 0, 0))
    write_png(str(tmp_path / "green.png"), (0, 255, 0))
    (tmp_path / "notes.txt").write_text("not a texture")
    env = build(
        sensor=[camera()],
        events=event(
            rand.randomize_visual_material,
            entity_cfg=E(uid="default_plane"),
            texture_path=str(tmp_path),
            random_texture_prob=1.0,
        ),
    )
    ids = apply(env, [0, 1, 2, 3])
    mat = env.scene.model.geom_matid[0]
    texid = field(env, "mat_texid")[:, mat, 1]
    from embodichain_functors.randomization.materials import texture_name

    green = env.scene.model.texture(texture_name(str(tmp_path / "green.png"))).id
    red = env.scene.model.texture(texture_name(str(tmp_path / "red.png"))).id
    assert set(texid.tolist()) <= {green, red}
    assert env.scene.model.ntex == 3
    assert (field(env, "mat_rgba")[ids, mat] == 1).all()  # textures are not tinted
    img = images(env)
    for i in ids.tolist():
        r, g = img[i, ..., 0].mean(), img[i, ..., 1].mean()
        assert (g > r + 30) if int(texid[i]) == green else (r > g + 30)


def test_texture_probability_zero_keeps_the_original_look(build, tmp_path) -> None:
    write_png(str(tmp_path / "red.png"), (255, 0, 0))
    env = build(
        events=event(
            rand.randomize_visual_material,
            entity_cfg=E(uid="cube"),
            texture_path=str(tmp_path),
            random_texture_prob=0.0,
        )
    )
    before = field(env, "mat_rgba"), field(env, "mat_texid")
    apply(env, IDS)
    assert torch.equal(field(env, "mat_rgba"), before[0])
    assert torch.equal(field(env, "mat_texid"), before[1])


def test_articulation_links_get_their_own_colours(build) -> None:
    env = build(
        events=event(
            rand.randomize_visual_material,
            entity_cfg=E(uid="arm"),
            base_color_range=[[0.0] * 3, [1.0] * 3],
            metallic_range=[0.2, 0.3],
        )
    )
    model = env.scene.model
    mats = sorted(
        {
            int(m)
            for m in model.geom_matid
            if m >= 0 and model.material(int(m)).name.startswith("embodichain_functors/mat/arm/")
        }
    )
    assert len(mats) >= 10  # base, 7 links, hand, fingers
    ids = apply(env, IDS)
    rgba = field(env, "mat_rgba")[:, mats]
    assert len({tuple(rgba[1, k, :3].tolist()) for k in range(len(mats))}) > 5  # drawn per link
    assert torch.equal(rgba[others(IDS)], torch.as_tensor(model.mat_rgba[mats]).expand(2, -1, -1))
    metallic = field(env, "mat_metallic")[:, mats]
    assert ((metallic[ids] >= 0.2) & (metallic[ids] <= 0.3)).all()


def test_set_material_with_a_texture_at_startup(build, tmp_path) -> None:
    tex = write_png(str(tmp_path / "blue.png"), (0, 0, 255))
    env = build(
        events={
            "mat": EventCfg(
                func=rand.set_rigid_object_visual_material,
                mode="startup",
                params={
                    "entity_cfg": E(uid="cube"),
                    "mat_cfg": {"base_color": [1.0, 1.0, 1.0], "base_color_texture": tex, "roughness": 0.3},
                },
            )
        }
    )
    mat = env.scene["cube"].material_id
    texid = field(env, "mat_texid")[:, mat, 1]
    assert (texid >= 0).all()
    assert env.scene.model.texture(int(texid[0])).name.startswith("embodichain_functors/tex")
    assert torch.allclose(field(env, "mat_roughness")[:, mat], torch.full((4,), 0.3), atol=1e-6)


def test_filter_visual_rand_drops_only_randomize_visual_functors(build) -> None:
    events = {
        "light": EventCfg(func=rand.randomize_light, params={"entity_cfg": E(uid="point"), "intensity_range": [0, 1]}),
        "mat": EventCfg(
            func=rand.randomize_visual_material,
            params={"entity_cfg": E(uid="cube"), "base_color_range": [[0] * 3, [1] * 3]},
        ),
        "named": EventCfg(func="randomize_light", params={"entity_cfg": E(uid="point"), "intensity_range": [0, 1]}),
        "set": EventCfg(
            func=rand.set_rigid_object_visual_material,
            mode="startup",
            params={"entity_cfg": E(uid="cube"), "mat_cfg": {"base_color": [1, 0, 0]}},
        ),
        "mass": EventCfg(
            func=rand.randomize_rigid_object_mass, params={"entity_cfg": E(uid="cube"), "mass_range": [1, 2]}
        ),
    }
    env = build(events=events, filter_visual_rand=True)
    assert sorted(env.event_manager.active_functors) == ["mass", "set"]


# -- cameras ---------------------------------------------------------------------------------------------
def test_camera_extrinsics_look_at_offsets(build) -> None:
    env = build(
        sensor=[camera()],
        events=event(
            rand.randomize_camera_extrinsics, entity_cfg=E(uid="cam"), eye_range=[[0.1, 0.1, 0.1], [0.2, 0.2, 0.2]]
        ),
    )
    cam = env.scene.sensors["cam"]
    pose0, before = cam.get_arena_pose(), images(env)
    ids = apply(env, IDS)
    apply(env, IDS)  # offsets from the configured eye: no drift
    pose = cam.get_arena_pose()
    delta = pose[ids, :3] - torch.tensor([0.5, -0.5, 0.5])
    assert ((delta >= 0.1 - 1e-5) & (delta <= 0.2 + 1e-5)).all()
    assert torch.equal(pose[others(IDS)], pose0[others(IDS)])
    assert changed(before, images(env)) == [i in IDS for i in range(4)]


def test_camera_extrinsics_offset_mode(build) -> None:
    ext = sensors.CameraCfg.ExtrinsicsCfg(pos=(0.5, -0.5, 0.5), quat=(0.92388, 0.38268, 0.0, 0.0))
    env = build(
        sensor=[camera(extrinsics=ext)],
        events=event(
            rand.randomize_camera_extrinsics,
            entity_cfg=E(uid="cam"),
            pos_range=[[0, 0, 0.1], [0, 0, 0.1]],
            euler_range=[[0, 0, 5], [0, 0, 5]],
        ),
    )
    apply(env, IDS)
    pose = env.scene.sensors["cam"].get_arena_pose()
    assert torch.allclose(pose[IDS, 2], torch.full((2,), 0.6), atol=1e-5)
    assert not torch.allclose(pose[1, 3:], pose[0, 3:])
    with pytest.raises(ConfigError, match="eye_range"):
        apply(
            build(
                sensor=[camera(extrinsics=ext)],
                events=event(
                    rand.randomize_camera_extrinsics, entity_cfg=E(uid="cam"), eye_range=[[0, 0, 0], [1, 1, 1]]
                ),
            ),
            IDS,
        )


def test_camera_intrinsics_offsets(build) -> None:
    env = build(
        sensor=[camera()],
        events=event(
            rand.randomize_camera_intrinsics,
            entity_cfg=E(uid="cam"),
            focal_x_range=[10, 20],
            focal_y_range=[10, 20],
            cx_range=[-2, 2],
        ),
    )
    cam = env.scene.sensors["cam"]
    before = images(env)
    ids = apply(env, IDS)
    k = cam.get_intrinsics()
    assert ((k[ids, 0, 0] >= 60) & (k[ids, 0, 0] <= 70)).all()
    assert (k[others(IDS), 0, 0] == 50).all()
    assert ((k[ids, 0, 2] - 32).abs() <= 2 + 1e-5).all()
    assert changed(before, images(env)) == [i in IDS for i in range(4)]


def test_camera_functors_reject_non_cameras(build) -> None:
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(rand.randomize_camera_intrinsics, entity_cfg=E(uid="cube"), cx_range=[0, 1])), IDS)
    assert err.value.path == "env.events.ev.params.entity_cfg"


@pytest.mark.parametrize(
    "func, params, param",
    [
        (rand.randomize_light, {"entity_cfg": E(uid="cube")}, "entity_cfg"),
        (rand.randomize_light, {"entity_cfg": E(uid="point"), "color_range": [[0, 0], [1, 1]]}, "color_range"),
        (
            rand.randomize_visual_material,
            {"entity_cfg": E(uid="cube"), "random_texture_prob": 1.5},
            "random_texture_prob",
        ),
        (rand.randomize_visual_material, {"entity_cfg": E(uid="point")}, "entity_cfg"),
        (
            rand.randomize_visual_material,
            {"entity_cfg": E(uid="cube"), "texture_path": "/no/such/folder"},
            "texture_path",
        ),
        (
            rand.set_rigid_object_visual_material,
            {"entity_cfg": E(uid="cube"), "mat_cfg": {"base_color": [2, 0, 0]}},
            "mat_cfg",
        ),
    ],
)
def test_bad_params(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(func, **params)), IDS)
    assert f"params.{param}" in str(err.value)
    assert func.__name__ in str(err.value)


# -- a camera without the sensor API: the MuJoCo camera fields are perturbed per env -----------------
def _bare_camera_plugin():
    from embodichain_core.plugins import hookimpl
    from embodichain_core.sim.cfg import SensorCfg
    from embodichain_core.sim.sensor_base import BaseSensor
    from embodichain_core.utils.configclass import configclass

    @configclass
    class BareCameraCfg(SensorCfg):
        sensor_type: str = "BareCamera"

    class BareCamera(BaseSensor):
        """Owns a MuJoCo camera named after its uid (64x48 pixels, 50 px focal length)."""

        def build(self, builder) -> None:
            cam = builder.spec.worldbody.add_camera(name=self.uid, pos=[0.5, -0.5, 0.5])
            cam.resolution, cam.sensor_size, cam.focal_pixel = [64, 48], [0.0064, 0.0048], [50.0, 50.0]

        def get_data(self) -> dict:
            return {}

    class Plugin:
        @hookimpl
        def embodichain_register_sensors(self, register) -> None:
            register("BareCamera", BareCameraCfg, BareCamera)

    return Plugin(), BareCameraCfg


def test_bare_mujoco_camera_fields_per_env(build, register_plugin) -> None:
    plugin, cfg_cls = _bare_camera_plugin()
    register_plugin(plugin, name="bare-camera")
    env = build(
        sensor=[cfg_cls(uid="bare")],
        events={
            "ext": EventCfg(
                func=rand.randomize_camera_extrinsics,
                mode="test",
                params={"entity_cfg": E(uid="bare"), "pos_range": [[0, 0, 0.1], [0, 0, 0.2]]},
            ),
            "int": EventCfg(
                func=rand.randomize_camera_intrinsics,
                mode="test",
                params={"entity_cfg": E(uid="bare"), "focal_x_range": [10, 10]},
            ),
        },
    )
    cam = env.scene.model.camera("bare").id
    pos0, intr0 = field(env, "cam_pos")[:, cam], field(env, "cam_intrinsic")[:, cam]
    ids = apply(env, IDS)
    pos, intr = field(env, "cam_pos")[:, cam], field(env, "cam_intrinsic")[:, cam]
    assert ((pos[ids, 2] - 0.5 >= 0.1 - 1e-9) & (pos[ids, 2] - 0.5 <= 0.2 + 1e-9)).all()
    assert torch.equal(pos[others(IDS)], pos0[others(IDS)])
    per_pixel = 0.0064 / 64
    assert torch.allclose(intr[ids, 0], intr0[ids, 0] + 10 * per_pixel)
    assert torch.equal(intr[others(IDS)], intr0[others(IDS)])
