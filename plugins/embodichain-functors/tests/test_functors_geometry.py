"""Geometry randomization: per-env scale of primitive objects (size, collision bounds,
inertia), visible to the body-scale observation; meshes are rejected."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import apply, event, field, others, write_box_obj

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import ObservationCfg
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import RigidObjectCfg
from embodichain_core.sim.shapes import MeshCfg

import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand

IDS = [0, 3]


def test_uniform_scale_of_a_box(build) -> None:
    env = build(events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="cube"),
                             scale_factor_range=[[1.5], [2.0]]),
                observations={"s": ObservationCfg(func=obs.get_object_body_scale, mode="add", name="object/scale",
                                                  params={"entity_cfg": E(uid="cube")})})
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
    assert torch.allclose(scale[ids], factor[:, None].float().expand(2, 3)) and (scale[others(IDS)] == 1).all()


def test_scaled_box_rests_on_the_ground_at_its_new_size(build) -> None:
    env = build(events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="cube"),
                             scale_factor_range=[[2.0, 2.0, 3.0], [2.0, 2.0, 3.0]], same_scale_all_axes=False))
    apply(env, IDS)
    for _ in range(30):
        env.step(torch.zeros(env.action_space.shape))
    z = env.scene["cube"].get_local_pose()[:, 2]
    assert torch.allclose(z[IDS], torch.full((2,), 0.075), atol=3e-3)  # half height 0.025 * 3
    assert torch.allclose(z[others(IDS)], torch.full((2,), 0.025), atol=3e-3)


def test_several_objects_with_a_shared_sample(build) -> None:
    env = build(events=event(rand.randomize_rigid_objects_scale, entity_cfgs=[E(uid="cube"), E(uid="ball")],
                             scale_factor_range=[0.5, 0.9], shared_sample=True))
    cube, ball = env.scene["cube"], env.scene["ball"]
    c0, b0 = field(env, "geom_size")[:, cube.geom_ids[0], 0], field(env, "geom_size")[:, ball.geom_ids[0], 0]
    apply(env, IDS)
    c1, b1 = field(env, "geom_size")[:, cube.geom_ids[0], 0], field(env, "geom_size")[:, ball.geom_ids[0], 0]
    assert torch.allclose(c1[IDS] / c0[IDS], b1[IDS] / b0[IDS])


def test_mesh_objects_are_rejected(build, tmp_path) -> None:
    mesh = RigidObjectCfg(uid="box", shape=MeshCfg(fpath=write_box_obj(str(tmp_path / "b.obj"), (0.02, 0.02, 0.02))),
                          init_pos=(0.3, -0.3, 0.02))
    with pytest.raises(ConfigError, match="not a primitive shape") as err:
        build(rigid_object=[mesh], events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="box"),
                                                scale_factor_range=[1, 2]))
    assert err.value.path == "env.events.ev.params.entity_cfg"


@pytest.mark.parametrize("rng", [[2.0, 1.0], [0.0, 1.0], [[1, 1], [2, 2]]])
def test_bad_ranges(build, rng) -> None:
    with pytest.raises(ConfigError, match="scale_factor_range"):
        apply(build(events=event(rand.randomize_rigid_object_scale, entity_cfg=E(uid="cube"), scale_factor_range=rng)),
              IDS)
