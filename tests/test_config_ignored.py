"""EmbodiChain fields at build: mapped ones change the simulation, the others are named
in one warning per build (embodichain_core.config.ignored)."""

from __future__ import annotations

import warnings
from typing import Any

import pytest
import torch
from core_testlib import base_cfg

from embodichain_core.config.ignored import IGNORED, IgnoredFieldWarning, ignored_fields
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.sim.shapes import MeshCfg


def _build(cfg: Any) -> tuple[EmbodiedEnv, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = EmbodiedEnv(cfg)
    return env, [w for w in caught if issubclass(w.category, IgnoredFieldWarning)]


def _odd_cfg() -> Any:
    cfg = base_cfg()
    cfg.sim_cfg.physics_config.enable_ccd = True
    cfg.sim_cfg.render_cfg.spp = 8
    cfg.sim_cfg.arena_space = 3.0
    cfg.rigid_object[0].attrs.sleep_threshold = 0.05
    cfg.rigid_object[0].attrs.max_linear_velocity = 2.0
    cfg.background[0].attrs.restitution = 0.4
    cfg.robot.build_pk_chain = False
    cfg.robot.attrs.mass = 3.0
    return cfg


def test_every_ignored_value_is_named_once_per_build_with_its_path_and_value() -> None:
    env, found = _build(_odd_cfg())
    env.close()
    assert len(found) == 1
    text = str(found[0].message)
    for line in (
        "sim_cfg.physics_config.enable_ccd = True",
        "sim_cfg.render_cfg.spp = 8",
        "sim_cfg.arena_space = 3.0",
        "rigid_object[0].attrs.sleep_threshold = 0.05",
        "rigid_object[0].attrs.max_linear_velocity = 2.0",
        "background[0].attrs.restitution = 0.4",
        "robot.build_pk_chain = False",
        "robot.attrs.mass = 3.0",
    ):
        assert line in text
    env, again = _build(_odd_cfg())  # a second build warns again, once
    env.close()
    assert len(again) == 1


def test_defaults_and_mapped_fields_give_no_warning() -> None:
    cfg = base_cfg()
    cfg.rigid_object[0].attrs.min_position_iters = 30  # mapped onto the solver iterations
    cfg.rigid_object[0].attrs.static_friction = 0.9  # mapped onto MuJoCo's sliding friction
    assert ignored_fields(cfg) == []
    env, found = _build(cfg)
    env.close()
    assert found == []


def test_mesh_and_render_fields_are_scanned() -> None:
    cfg = base_cfg()
    cfg.rigid_object[0].shape = MeshCfg(fpath="x.obj", sdf_resolution=64)
    cfg.sim_cfg.render_cfg.renderer = "rt"
    paths = {f.path for f in ignored_fields(cfg)}
    assert paths == {"rigid_object[0].shape.sdf_resolution", "sim_cfg.render_cfg.renderer"}


def test_light_fields_without_a_mujoco_twin_are_reported() -> None:
    cfg = base_cfg()
    light = cfg.light.direct[0]
    light.light_type, light.rect_width, light.halo_size = "rect", 2.0, 0.5
    paths = {f.path for f in ignored_fields(cfg)}
    assert paths == {"light.direct[0].light_type", "light.direct[0].rect_width", "light.direct[0].halo_size"}


def test_the_table_explains_every_field() -> None:
    assert all(why.strip() for fields in IGNORED.values() for why in fields.values())


def _cube_after_steps(min_position_iters: int) -> tuple[int, torch.Tensor]:
    cfg = base_cfg()
    cfg.sim_cfg.physics_config.iterations = 1
    cfg.sim_cfg.physics_config.solver = "PGS"
    cfg.rigid_object[0].attrs.min_position_iters = min_position_iters
    env = EmbodiedEnv(cfg)
    try:
        env.reset(seed=0)
        for _ in range(20):
            env.step(torch.zeros(env.action_space.shape))
        return int(env.scene.model.opt.iterations), env.scene["cube"].get_local_pose().clone()
    finally:
        env.close()


def test_min_solver_iterations_raise_mujocos_iterations_and_change_the_simulation() -> None:
    few_iters, few = _cube_after_steps(4)
    many_iters, many = _cube_after_steps(100)
    assert (few_iters, many_iters) == (5, 101)  # min_position_iters + min_velocity_iters (1)
    assert not torch.allclose(few, many)


@pytest.mark.parametrize("owner", ["robot", "robot.attrs"])
def test_an_articulations_iteration_counts_are_mapped_too(owner: str) -> None:
    cfg = base_cfg()
    target = cfg.robot if owner == "robot" else cfg.robot.attrs
    target.min_velocity_iters = 70
    env = EmbodiedEnv(cfg)
    try:
        assert env.scene.model.opt.iterations == 74  # 4 + 70, above physics_config.iterations (50)
    finally:
        env.close()


def _cube_tree_asleep(cfg: Any, steps: int = 60) -> tuple[Any, bool]:
    env = EmbodiedEnv(cfg)
    try:
        env.reset(seed=0)
        for _ in range(steps):
            env.step(torch.zeros(env.action_space.shape))
        model, data = env.scene.model, env.sim.get_data(0)
        tree = int(model.body_treeid[env.scene["cube"].body_id])
        return model, bool(data.tree_asleep[tree] >= 0)
    finally:
        env.close()


def test_sleep_threshold_maps_onto_mujocos_sleeping_when_enabled() -> None:
    import mujoco

    cfg = base_cfg()
    model, asleep = _cube_tree_asleep(cfg)
    assert not asleep  # sleeping is off by default
    assert not model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    cfg = base_cfg()
    cfg.sim_cfg.physics_config.enable_sleep = True
    cfg.rigid_object[0].attrs.sleep_threshold = 0.002
    model, asleep = _cube_tree_asleep(cfg)
    assert asleep  # the resting cube's tree sleeps
    assert model.opt.sleep_tolerance == pytest.approx((2 * 0.002) ** 0.5)  # the speed of that energy per kg
    assert ignored_fields(cfg) == []  # mapped, so not reported
    cfg.rigid_object[0].attrs.sleep_threshold = 0.0  # 0: never sleeps
    model, asleep = _cube_tree_asleep(cfg)
    assert not asleep
    assert int(mujoco.mjtSleepPolicy.mjSLEEP_NEVER) in model.tree_sleep_policy.tolist()


@pytest.mark.parametrize("edit", ["warp", "not_persistent"])
def test_sleeping_needs_a_persistent_cpu_batch(edit: str) -> None:
    from embodichain_core.config.errors import ConfigError

    cfg = base_cfg()
    cfg.sim_cfg.physics_config.enable_sleep = True
    if edit == "warp":
        cfg.sim_cfg.backend = "warp"
    else:
        cfg.sim_cfg.persistent = False
    with pytest.raises(ConfigError) as err:
        cfg.validate(memory=False)
    assert err.value.path == "sim_cfg.physics_config.enable_sleep"
