"""Fixtures of the embodichain-robots tests: built scenes (module scoped, they are reused)."""

from __future__ import annotations

from typing import Any, Callable

import pytest


def make_scene(cfg: Any, num_envs: int = 2) -> Any:
    """A scene with only ``cfg``'s robot, built."""
    from embodichain_core.sim.cfg import SimulationManagerCfg
    from embodichain_core.sim.scene import Scene

    scene = Scene(SimulationManagerCfg(), num_envs=num_envs)
    scene.add_robot(cfg)
    scene.build()
    return scene


@pytest.fixture(scope="module")
def w1() -> Any:
    """The seed tutorial's W1 (two envs), as a built ``Robot``."""
    from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg

    cfg = DexforceW1Cfg.from_dict(
        {"uid": "dexforce_w1", "version": "v021", "arm_kind": "anthropomorphic", "init_pos": [0, 0, 0]}
    )
    return make_scene(cfg)["dexforce_w1"]


@pytest.fixture(scope="module")
def arm() -> Any:
    """The 7-DoF arm (two envs), as a built ``Robot``."""
    from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg

    return make_scene(SevenDofArmCfg.from_dict({"uid": "arm"}))["arm"]


@pytest.fixture
def scene_factory() -> Callable[..., Any]:
    """``scene_factory(cfg, num_envs=2) -> Scene``."""
    return make_scene
