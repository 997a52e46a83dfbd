"""The seed tutorial's scene: the table stands up, forks rest on it, fork meshes swap per env."""

from __future__ import annotations

import mujoco
import numpy as np
import torch

from embodichain_assets import seed_scene
from embodichain_assets.seed_scene import TABLE_TOP_Z, build_seed_scene, fork_variant_files

SETTLE_STEPS = 150  # 1.5 s of simulated time


def _geom_world_z(scene, body: str) -> tuple[float, float]:
    """Lowest and highest world z of the collision geoms' vertices of ``body`` in env 0."""
    model, data = scene.model, scene.sim.get_data(0)
    body_id = model.body(body).id
    zs = []
    for geom in np.flatnonzero(model.geom_bodyid == body_id):
        if model.geom_contype[geom] == 0 or model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        mesh = model.geom_dataid[geom]
        local = model.mesh_vert[model.mesh_vertadr[mesh] : model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
        zs.append(local @ data.geom_xmat[geom].reshape(3, 3)[2] + data.geom_xpos[geom][2])
    zs = np.concatenate(zs)
    return float(zs.min()), float(zs.max())


def _half_thickness(fpath: str) -> float:
    from embodichain_core.sim.scene_build.mesh import load_mesh

    lo, hi = load_mesh(fpath, scale=seed_scene.FORK_SCALE).bounds
    return float(hi[2] - lo[2]) / 2.0


def test_round_table_stands_up_with_the_tutorial_pose():
    scene = build_seed_scene()
    bottom, top = _geom_world_z(scene, "table")
    assert abs(top - TABLE_TOP_Z) < 1e-5
    assert abs(bottom) < 1e-5
    rot = scene.sim.xmat[0, scene.model.body("table").id].reshape(3, 3).numpy()
    np.testing.assert_allclose(rot @ [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], atol=1e-9)  # mesh -X is world up


def test_fork_dropped_by_the_tutorial_rests_on_the_table():
    scene = build_seed_scene()
    fork = scene["fork"]
    assert torch.allclose(fork.get_local_pose()[0, :3].double(), torch.tensor(seed_scene.FORK_POS, dtype=torch.float64))
    scene.sim.step(SETTLE_STEPS)
    pose = fork.get_local_pose()[0].double()
    expected = TABLE_TOP_Z + _half_thickness(fork_variant_files()[-1])  # standard_fork_scale.ply sorts last
    # objects rest on the surface (contact margins are PhysX's rest_offset, 0 by default)
    assert expected - 1e-3 < float(pose[2]) < expected + 1e-3, (float(pose[2]), expected)
    assert torch.allclose(pose[:2], torch.tensor(seed_scene.FORK_POS[:2], dtype=torch.float64), atol=0.01)
    assert abs(float(pose[3])) > 0.999  # still lying flat
    assert float(scene.sim.qvel[0, :6].abs().max()) < 1e-2  # at rest


def test_fork_variants_swap_per_env_and_all_rest_on_the_table():
    files = fork_variant_files()
    assert len(files) >= 5
    scene = build_seed_scene(num_envs=len(files), fork_variants=files)
    for env, fpath in enumerate(files):
        scene.set_mesh_variant("fork", fpath, env_ids=[env])
    assert scene.current_mesh["fork"] == files
    scene.sim.step(SETTLE_STEPS)
    z = scene["fork"].get_local_pose()[:, 2].double().numpy()
    expected = np.array([TABLE_TOP_Z + _half_thickness(f) for f in files])
    # every fork lies on the table top; a bent fork's centre sits below its bounding box's half height
    assert np.all(z > TABLE_TOP_Z), (z, expected)
    assert np.all(z < expected + 1e-3), (z, expected)
    assert float(scene.sim.qvel[:, :6].abs().max()) < 1e-2
    # each env collides with its own fork only: the enabled collision geoms differ between envs
    contype = scene.sim.model_field("geom_contype")
    enabled = [tuple(np.flatnonzero(row == 1)) for row in contype]
    assert len(set(enabled)) == len(files)
