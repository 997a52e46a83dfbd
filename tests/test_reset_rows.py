"""Resets from the saved default state row (``embodichain_core.sim.scene_defaults``) give
exactly what the reset that rewrites every entity gives, and the row is dropped when
what it was derived from changes."""

from __future__ import annotations

import numpy as np
import torch

from core_testlib import ARM_ACTIVE


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
    assert env.scene.defaults.row() is None  # the build resets entities only
    env.reset()
    assert env.scene.defaults.row() is not None  # the first reset saved it
    calls = []
    cube = env.scene["cube"]
    cube.reset = lambda env_ids=None: calls.append(env_ids)  # an instance attribute: the class reset still covers it
    env.reset(options={"reset_ids": [1]})
    assert calls == []  # restored from the row, not rewritten
    assert np.array_equal(env.sim.state[1], env.scene.defaults.row())


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
