"""Per-env mesh variants: envs of one batch run different meshes of one object, on both
backends (``warp`` parks the unused variants' geoms out of reach instead of switching their
collision bits)."""

import numpy as np
import pytest
import torch
import trimesh

from embodichain_core.sim.cfg import RigidObjectCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import MeshCfg


def _write(tmp_path, name, mesh):
    path = tmp_path / name
    mesh.export(path)
    return str(path)


@pytest.mark.parametrize("backend", ["mujoco_batch", "warp"])
def test_envs_run_different_meshes_and_collide_with_their_own(tmp_path, backend):
    small = _write(tmp_path, "small.obj", trimesh.creation.box((0.04, 0.04, 0.04)))
    tall = _write(tmp_path, "tall.obj", trimesh.creation.box((0.04, 0.04, 0.20)))
    two = _write(
        tmp_path,
        "two.obj",
        trimesh.util.concatenate(
            [
                trimesh.creation.box((0.04, 0.04, 0.04)),
                trimesh.creation.box((0.04, 0.04, 0.04)).apply_translation((0.1, 0, 0)),
            ]
        ),
    )
    scene = Scene(SimulationManagerCfg(backend=backend), num_envs=3)
    scene.add_rigid_object(RigidObjectCfg(uid="obj", shape=MeshCfg(fpath=small), init_pos=(0, 0, 0.3)))
    scene.reserve_mesh_variants("obj", [small, tall, two])
    scene.build()
    obj = scene["obj"]
    scene.set_mesh_variant("obj", tall, env_ids=[1])
    scene.set_mesh_variant("obj", two, env_ids=[2])
    for _ in range(150):
        scene.sim.step(1)
    z = obj.get_local_pose()[:, 2].double()
    # resting heights follow each env's own mesh: half-heights 0.02, 0.10, 0.02
    assert torch.allclose(z, torch.tensor([0.02, 0.10, 0.02], dtype=torch.float64), atol=6e-3), z
    assert scene.current_mesh["obj"] == [small, tall, two]
    # per-env model fields still work with mesh variants, only for the chosen env
    obj.set_mass([1.0, 2.0, 3.0])
    assert torch.allclose(obj.get_mass().double(), torch.tensor([1.0, 2.0, 3.0], dtype=torch.float64))
    # env 0 collides with its own mesh only: the tall variant's geoms are off (parked) there
    if backend == "warp":
        from embodichain_core.sim.scene_build.variants import PARK_HEIGHT

        high = np.asarray(scene.sim.model_field("geom_pos"))[:, :, 2] >= PARK_HEIGHT
        # the geoms of the variants an env does not use (2 small, 2 tall, 3 two) are parked
        assert high.sum(axis=1).tolist() == [5, 5, 4], high
        assert not np.array_equal(high[0], high[1])
        assert not np.array_equal(high[1], high[2])
        return
    contype = scene.sim.model_field("geom_contype")
    assert contype[0].sum() < contype[1].sum() + contype[2].sum()


def test_unreserved_variant_is_a_clear_error(tmp_path):
    one = _write(tmp_path, "one.obj", trimesh.creation.box((0.04, 0.04, 0.04)))
    other = _write(tmp_path, "other.obj", trimesh.creation.box((0.04, 0.04, 0.08)))
    scene = Scene(SimulationManagerCfg(), num_envs=2)
    scene.add_rigid_object(RigidObjectCfg(uid="obj", shape=MeshCfg(fpath=one), init_pos=(0, 0, 0.3)))
    scene.build()
    try:
        scene.set_mesh_variant("obj", other, env_ids=[0])
    except ValueError as err:
        assert "reserve_mesh_variants" in str(err)
        assert "obj" in str(err)
    else:
        raise AssertionError("expected a ValueError")
