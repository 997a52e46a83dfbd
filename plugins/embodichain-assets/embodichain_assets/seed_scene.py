"""The seed tutorial's scene (``modular_env``) without the robot and the camera.

A kinematic ``CircleTableSimple`` at (0.80, 0, 0.8) turned by ``init_rot=(0, 90, 0)`` with
``compute_uv``, the standard fork dropped at (0.8, 0, 1.0) with ``body_scale=(0.75, 0.75, 1)``,
the ``SlidingBoxDrawer`` at (0.5, 0, 0.85) and a point light at (0, 0, 2): the configuration the
tests, the scene-build benchmark and the docs' overview image share.

Example:
    >>> scene = build_seed_scene(num_envs=2)  # doctest: +SKIP
    >>> scene.sim.step(200)  # doctest: +SKIP
    >>> scene["fork"].get_local_pose()[:, 2]  # ~0.8225 (+ contact offset)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Sequence

from embodichain_assets import catalog

TABLE_POS = (0.80, 0.0, 0.8)
TABLE_ROT = (0.0, 90.0, 0.0)
FORK_POS = (0.8, 0.0, 1.0)
FORK_SCALE = (0.75, 0.75, 1.0)
DRAWER_POS = (0.5, 0.0, 0.85)
TABLE_TOP_Z = TABLE_POS[2] + 0.02  # the slab's top surface is 0.02 along the table's up axis


def seed_scene_cfgs() -> dict[str, Any]:
    """The configs of the scene, keyed by role: ``table``, ``fork``, ``drawer``, ``light``."""
    from embodichain_core.sim.cfg import ArticulationCfg, LightCfg, RigidBodyAttributesCfg, RigidObjectCfg
    from embodichain_core.sim.data import get_data_path
    from embodichain_core.sim.shapes import MeshCfg

    table = RigidObjectCfg(
        uid="table",
        shape=MeshCfg(fpath=get_data_path(catalog.CIRCLE_TABLE), compute_uv=True),
        attrs=RigidBodyAttributesCfg(mass=10.0, static_friction=0.95, dynamic_friction=0.85, restitution=0.01),
        body_type="kinematic",
        init_pos=TABLE_POS,
        init_rot=TABLE_ROT,
    )
    fork = RigidObjectCfg(
        uid="fork", shape=MeshCfg(fpath=get_data_path(catalog.STANDARD_FORK)), body_scale=FORK_SCALE, init_pos=FORK_POS
    )
    drawer = ArticulationCfg(uid="drawer", fpath=catalog.DRAWER, init_pos=DRAWER_POS)
    light = LightCfg(uid="point", light_type="point", color=(1.0, 1.0, 1.0), intensity=20.0, init_pos=(0, 0, 2))
    return {"table": table, "fork": fork, "drawer": drawer, "light": light}


def fork_variant_files() -> list[str]:
    """Every file of the fork folder, sorted (what ``replace_assets_from_group`` picks from)."""
    import os

    from embodichain_core.sim.data import get_data_path

    folder = get_data_path(catalog.FORK_FOLDER)
    return [os.path.join(folder, f) for f in sorted(os.listdir(folder))]


def build_seed_scene(
    num_envs: int = 1, fork_variants: Sequence[str] | None = None, robot_cfg: Any = None, sim_cfg: Any = None
) -> Any:
    """Build the scene (optionally with fork mesh variants reserved and a robot) and return it.

    Args:
        num_envs: parallel envs.
        fork_variants: mesh files the fork may swap to per env (``reserve_mesh_variants``).
        robot_cfg: a robot config added first, as in the tutorial (optional).
        sim_cfg: a ``SimulationManagerCfg`` (default settings when None).
    """
    from embodichain_core.sim.cfg import SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    cfgs = seed_scene_cfgs()
    scene = Scene(sim_cfg if sim_cfg is not None else SimulationManagerCfg(), num_envs=num_envs)
    if robot_cfg is not None:
        scene.add_robot(robot_cfg)
    scene.add_rigid_object(cfgs["table"], background=True)
    scene.add_rigid_object(cfgs["fork"])
    scene.add_articulation(cfgs["drawer"])
    scene.add_light(cfgs["light"])
    if fork_variants:
        scene.reserve_mesh_variants("fork", list(fork_variants))
    scene.build()
    return scene
