"""Geometry randomization: per-env scale of primitive objects (size, collision bounds,
inertia) and of mesh objects (precompiled scaled copies), visible to the body-scale
observation."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import apply, event, field, others, write_box_obj

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg, ObservationCfg
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import RigidObjectCfg
from embodichain_core.sim.shapes import MeshCfg

import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand

IDS = [0, 3]


def test_uniform_scale_of_a_box(build) -> None:
    env = build(
        events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="cube"), scale_factor_range=[[1.5], [2.0]]),
        observations={
            "s": ObservationCfg(
                func=obs.get_object_body_scale, mode="add", name="object/scale", params={"entity_cfg": E(uid="cube")}
            )
        },
    )
    cube = env.scene["cube"]
    geom, body = cube.geom_ids[0], cube.body_id
    size0, inertia0 = field(env, "geom_size")[:, geom], field(env, "body_inertia")[:, body]
    ids = apply(env, IDS)
    size, inertia = field(env, "geom_size")[:, geom], field(env, "body_inertia")[:, body]
    factor = size[ids, 0] / size0[ids, 0]
    assert ((factor >= 1.5) & (factor <= 2.0)).all()
    assert torch.allclose(size[ids], size0[ids] * factor[:, None])
    assert torch.allclose(inertia[ids], inertia0[ids] * factor[:, None] ** 2)  # same mass, s^2 inertia
    assert torch.allclose(field(env, "geom_rbound")[ids, geom], size[ids].norm(dim=-1))
    assert torch.equal(size[others(IDS)], size0[others(IDS)])
    scale = env.get_obs()["object"]["scale"]
    assert torch.allclose(scale[ids], factor[:, None].float().expand(2, 3))
    assert (scale[others(IDS)] == 1).all()


def test_scaled_box_rests_on_the_ground_at_its_new_size(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_object_scale,
            entity_cfg=E(uid="cube"),
            scale_factor_range=[[2.0, 2.0, 3.0], [2.0, 2.0, 3.0]],
            same_scale_all_axes=False,
        )
    )
    apply(env, IDS)
    for _ in range(30):
        env.step(torch.zeros(env.action_space.shape))
    z = env.scene["cube"].get_local_pose()[:, 2]
    assert torch.allclose(z[IDS], torch.full((2,), 0.075), atol=3e-3)  # half height 0.025 * 3
    assert torch.allclose(z[others(IDS)], torch.full((2,), 0.025), atol=3e-3)


def test_several_objects_with_a_shared_sample(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_objects_scale,
            entity_cfgs=[E(uid="cube"), E(uid="ball")],
            scale_factor_range=[0.5, 0.9],
            shared_sample=True,
        )
    )
    cube, ball = env.scene["cube"], env.scene["ball"]
    c0, b0 = field(env, "geom_size")[:, cube.geom_ids[0], 0], field(env, "geom_size")[:, ball.geom_ids[0], 0]
    apply(env, IDS)
    c1, b1 = field(env, "geom_size")[:, cube.geom_ids[0], 0], field(env, "geom_size")[:, ball.geom_ids[0], 0]
    assert torch.allclose(c1[IDS] / c0[IDS], b1[IDS] / b0[IDS])


def _mesh_box(tmp_path, uid: str = "box", z: float = 0.02) -> RigidObjectCfg:
    path = write_box_obj(str(tmp_path / f"{uid}.obj"), (0.02, 0.02, 0.02))
    return RigidObjectCfg(uid=uid, shape=MeshCfg(fpath=path), init_pos=(0.3, -0.3, z))


def test_mesh_object_takes_the_nearest_precompiled_scale(build, tmp_path) -> None:
    env = build(
        rigid_object=[_mesh_box(tmp_path)],
        events=event(
            rand.randomize_rigid_object_scale,
            entity_cfg=E(uid="box"),
            scale_factor_range=[1.0, 3.0],
            mesh_scale_levels=4,
        ),
        observations={
            "s": ObservationCfg(
                func=obs.get_object_body_scale, mode="add", name="object/scale", params={"entity_cfg": E(uid="box")}
            )
        },
    )
    box = env.scene["box"]
    mass0, inertia0 = field(env, "body_mass")[:, box.body_id], field(env, "body_inertia")[:, box.body_id]
    apply(env, [0, 1, 2, 3])
    scale = env.get_obs()["object"]["scale"][:, 0].double()
    levels = torch.tensor([1.25, 1.75, 2.25, 2.75], dtype=torch.float64)  # bin centres of [1, 3]
    assert all(torch.isclose(levels, s).any() for s in scale)
    assert torch.allclose(field(env, "body_mass")[:, box.body_id], mass0)  # the mass is kept
    inertia = field(env, "body_inertia")[:, box.body_id]
    assert torch.allclose(inertia, inertia0 * scale[:, None] ** 2, rtol=1e-4)
    env.scene["box"].set_local_pose(torch.tensor([[0.3, -0.3, 0.2, 1.0, 0, 0, 0]]).expand(4, 7))
    for _ in range(40):
        env.step(torch.zeros(env.action_space.shape))
    z = env.scene["box"].get_local_pose()[:, 2].double()
    assert torch.allclose(z, 0.02 * scale, atol=3e-3)  # rests on its scaled half height


def test_mesh_scale_per_axis_uses_a_grid(build, tmp_path) -> None:
    env = build(
        rigid_object=[_mesh_box(tmp_path)],
        events=event(
            rand.randomize_rigid_object_scale,
            entity_cfg=E(uid="box"),
            scale_factor_range=[[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]],
            same_scale_all_axes=False,
            mesh_scale_levels=8,
        ),
    )
    variants = env.scene.builder.records["box"].extra["variants"]
    assert len([v for v in variants.values() if v.get("factor")]) == 8  # 2 values per axis
    apply(env, [0, 1, 2, 3])
    keys = set(env.scene.current_mesh["box"])
    assert keys <= {k for k, v in variants.items() if v.get("factor")}


def test_mesh_scaling_and_mesh_swapping_do_not_combine(build, tmp_path) -> None:
    import embodichain_functors.events as events

    folder = tmp_path / "meshes"
    folder.mkdir()
    for k in range(2):
        write_box_obj(str(folder / f"m{k}.obj"), (0.02 + 0.01 * k,) * 3)
    evs = {
        **event(events.replace_assets_from_group, entity_cfg=E(uid="box"), folder_path=str(folder)),
        "scale": EventCfg(
            func=rand.randomize_rigid_object_scale,
            mode="test",
            params={"entity_cfg": E(uid="box"), "scale_factor_range": [1, 2]},
        ),
    }
    with pytest.raises(ConfigError, match="also swaps meshes"):
        build(rigid_object=[_mesh_box(tmp_path)], events=evs)


@pytest.mark.parametrize("rng", [[2.0, 1.0], [0.0, 1.0], [[1, 1], [2, 2]]])
def test_bad_ranges(build, rng) -> None:
    with pytest.raises(ConfigError, match="scale_factor_range"):
        apply(
            build(events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="cube"), scale_factor_range=rng)),
            IDS,
        )
