"""Resets from the saved default state row (``embodichain_core.sim.scene_defaults``) give
exactly what the reset that rewrites every entity gives, and the row is dropped when
what it was derived from changes."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from core_testlib import ARM_ACTIVE

from embodichain_core.sim.cfg import ArticulationCfg, RigidObjectCfg, SimulationManagerCfg
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import CubeCfg

FLOATING_MJCF = """
<mujoco model="float">
  <worldbody>
    <body name="base" pos="0 0 0.3">
      <geom type="box" size="0.05 0.05 0.05" mass="1"/>
      <body name="arm" pos="0.1 0 0">
        <joint name="hinge" type="hinge" axis="0 0 1" range="-1 1"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _slow_only(env):
    """Never save a row: every reset runs the model reset and every entity's reset."""
    env.scene.defaults.capture = lambda env_ids: None
    return env


def _drive(envs, steps, seed):
    gen = torch.Generator().manual_seed(seed)
    for _ in range(steps):
        action = (torch.rand(2, ARM_ACTIVE, generator=gen) - 0.5).float()
        outs = [env.step(action) for env in envs]
    return outs


def test_the_row_is_saved_by_the_first_reset_and_used_after(make_env) -> None:
    env = make_env()
    assert env.scene.defaults.row() is not None  # the build's scene reset saved it
    env.reset()
    assert env.scene.defaults.row() is not None
    calls = []
    cube = env.scene["cube"]
    cube.reset = lambda env_ids=None: calls.append(env_ids)  # an instance attribute: the class declares state-only
    env.reset(options={"reset_ids": [1]})
    assert calls == []  # restored from the row, not rewritten
    assert np.array_equal(env.sim.state[1], env.scene.defaults.row())


def test_a_subclass_overriding_reset_runs_with_the_row(make_env) -> None:
    calls: list[Any] = []

    class CountingCube(RigidObject):  # overrides reset without declaring it state-only
        def reset(self, env_ids: Any = None) -> None:
            calls.append(env_ids)
            super().reset(env_ids)

    class PlainCube(RigidObject):  # declares its reset state-only again
        state_only_reset = True

        def reset(self, env_ids: Any = None) -> None:
            calls.append("plain")
            super().reset(env_ids)

    assert not CountingCube.state_only_reset
    assert PlainCube.state_only_reset
    env = make_env()
    env.reset()
    cube = env.scene["cube"]
    cube.__class__ = CountingCube
    env.reset(options={"reset_ids": [1]})
    assert env.scene.defaults.row() is not None
    assert [c.tolist() for c in calls] == [[1]]
    cube.__class__ = PlainCube
    env.reset(options={"reset_ids": [1]})
    assert len(calls) == 1  # skipped: the row holds what it writes


def test_row_resets_match_entity_resets_bit_for_bit(make_env) -> None:
    fast, slow = make_env(), _slow_only(make_env())
    for env in (fast, slow):
        env.reset(seed=3)
    _drive((fast, slow), 5, seed=0)
    for env in (fast, slow):
        env.scene["cube"].set_velocity(torch.tensor([[0.3, 0.0, 0.0, 0.0, 0.0, 1.0]] * 2))
        env.reset(options={"reset_ids": [0]})
    assert np.array_equal(fast.sim.state, slow.sim.state)
    (obs_f, rew_f, *_), (obs_s, rew_s, *_) = _drive((fast, slow), 4, seed=1)
    assert np.array_equal(fast.sim.state, slow.sim.state)
    for key in ("qpos", "qvel", "qf"):
        assert torch.equal(obs_f["robot"][key], obs_s["robot"][key]), key
    assert float(obs_s["robot"]["qvel"].abs().sum()) > 0  # the envs really moved


def test_a_changed_default_drops_the_row(make_env) -> None:
    env = make_env()
    env.reset()
    robot = env.robot
    robot.default_qpos[0] = 0.5  # a new initial joint position, set in place
    env.reset(options={"reset_ids": [1]})
    assert env.robot.get_qpos()[1, 0].item() == 0.5
    assert env.robot.get_qpos()[0, 0].item() != 0.5
    assert env.scene.defaults.row() is not None  # saved again, with the new default
    env.step(torch.zeros(2, ARM_ACTIVE))
    env.reset(options={"reset_ids": [0]})
    assert env.robot.get_qpos()[0, 0].item() == 0.5


def test_detached_entities_keep_their_state_with_the_row(make_env) -> None:
    env = make_env()
    env.reset()
    env.add_detached_uids_for_reset("cube")
    moved = torch.tensor([[0.3, 0.2, 0.05, 1.0, 0.0, 0.0, 0.0]] * 2, dtype=torch.float64)
    env.scene["cube"].set_local_pose(moved)
    env.robot.set_qpos(torch.full((2, ARM_ACTIVE), 0.3), joint_ids=list(range(ARM_ACTIVE)), target=False)
    env.reset(options={"reset_ids": [1]})
    assert torch.allclose(env.scene["cube"].get_local_pose()[1].double(), moved[1], atol=1e-6)
    assert env.robot.get_qpos()[1, 0].item() != 0.3  # the rest went back to the defaults


def test_per_env_model_defaults_use_the_model_reset(make_env) -> None:
    env = make_env()
    env.reset()
    assert env.scene.defaults.row() is not None
    env.sim.declare_per_env(["qpos0"])
    assert env.scene.defaults.row() is None
    env.reset()
    assert env.scene.defaults.row() is None  # not saved again while qpos0 is per env


def _floating_scene(save_rows: bool = True) -> Scene:
    scene = Scene(SimulationManagerCfg(), 2)
    scene.add_articulation(ArticulationCfg(uid="float", mjcf=FLOATING_MJCF, fix_base=False, init_qpos=[0.2]))
    scene.add_rigid_object(RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.1, 0.1, 0.1]), init_pos=(0.5, 0, 0.05)))
    if not save_rows:
        scene.defaults.capture = lambda env_ids: None  # type: ignore[method-assign]
    scene.build()
    return scene


def test_a_changed_initial_root_pose_drops_the_row() -> None:
    scene = _floating_scene()
    art = scene["float"]
    assert art.is_floating
    assert scene.defaults.row() is not None
    scene.sim.qpos[:, art.root_qpos_adr] += 0.25  # the bases move away
    art.init_root_pose[:3] = torch.tensor([0.3, -0.2, 0.6], dtype=torch.float64)  # a new start, set in place
    scene.reset([1])
    pose = art.get_local_pose().double()
    assert torch.allclose(pose[1], art.init_root_pose)
    assert not torch.allclose(pose[0], art.init_root_pose)
    assert scene.defaults.row() is not None  # saved again, with the new start
    scene.sim.qpos[:, art.root_qpos_adr] += 0.25
    scene.reset([0])
    assert torch.allclose(art.get_local_pose()[0].double(), art.init_root_pose)


def test_every_declared_initial_value_reaches_a_row_reset() -> None:
    """Change each value any state-only entity declares its reset reads: a reset from the
    saved row gives bit for bit what the entity resets give."""
    fast, slow = _floating_scene(), _floating_scene(save_rows=False)
    for scene in (fast, slow):
        scene.reset()
    checked = 0
    for uid, ent in fast.entities.items():
        assert ent.state_only_reset, uid
        for k, value in enumerate(ent.initial_state()):
            for scene in (fast, slow):
                arr = scene[uid].initial_state()[k]
                arr[0] += 0.125  # in place: the entity's own initial state
                scene.sim.step(3)
                scene.reset([1])  # a stale row would give the old value here
                scene.sim.step(3)
                scene.reset([0])  # from the row saved again (fast)
            assert np.array_equal(fast.sim.state, slow.sim.state), (uid, k)
            checked += 1
    assert checked == 3  # the cube's pose, the joint defaults and the root pose
    assert fast.defaults.row() is not None
    assert slow.defaults.row() is None
