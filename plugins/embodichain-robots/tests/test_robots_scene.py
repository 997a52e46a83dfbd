"""Both robots in a Scene: build, hold the home pose under gravity, Robot kinematics API."""

from __future__ import annotations

import pytest
import torch

from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg
from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg
from embodichain_robots.kinematics.solver import sample_joint_values


@pytest.mark.parametrize(
    "make",
    [
        lambda: DexforceW1Cfg.from_dict({"uid": "robot"}),
        lambda: DexforceW1Cfg.from_dict({"uid": "robot", "arm_kind": "industrial", "gravity_compensation": False}),
        lambda: DexforceW1Cfg.from_dict({"uid": "robot", "gravity_compensation": False}),
        lambda: SevenDofArmCfg.from_dict({"uid": "robot"}),
        lambda: SevenDofArmCfg.from_dict({"uid": "robot", "gravity_compensation": False}),
    ],
    ids=["w1", "w1_industrial_nogravcomp", "w1_nogravcomp", "arm", "arm_nogravcomp"],
)
def test_holds_home_pose_for_one_second(scene_factory: object, make: object) -> None:
    scene = scene_factory(make(), num_envs=2)
    robot = scene["robot"]
    home = robot.get_qpos().clone()
    steps = round(1.0 / scene.sim_cfg.physics_dt)
    for _ in range(steps):
        assert scene.sim.step(1) == []
    qpos = robot.get_qpos()
    assert bool(torch.isfinite(qpos).all())
    tol = 1e-6 if robot.cfg.gravity_compensation else 1e-2
    assert float((qpos - home).abs().max()) < tol
    assert float(robot.get_qvel().abs().max()) < 1e-2


def test_part_fk_matches_tcp_site(w1: object, arm: object) -> None:
    for robot, part, site in ((w1, "left_arm", "left_tcp"), (w1, "right_arm", "right_tcp"), (arm, "arm", "tcp")):
        model = robot.scene.model
        sid = model.site(f"{robot.uid}/{site}").id
        pose = robot.compute_fk(name=part)
        assert torch.allclose(pose[:, :3, 3], robot.sim.site_xpos[:, sid].float(), atol=1e-5)
        assert torch.allclose(pose[:, :3, :3].reshape(2, 9), robot.sim.site_xmat[:, sid].float(), atol=1e-5)


def test_compute_fk_accepts_part_or_full_qpos(w1: object) -> None:
    ids = w1.get_joint_ids("left_arm")
    full = torch.zeros(2, w1.dof)
    full[:, 0:3] = torch.tensor([0.5, -1.0, 0.5])  # crouch: the arm base moves too
    full[:, ids] = 0.3
    crouched = w1.compute_fk(full, name="left_arm")
    at_current_base = w1.compute_fk(full[:, ids], name="left_arm")
    assert crouched[0, 2, 3] < at_current_base[0, 2, 3] - 0.05
    pose7 = w1.compute_fk(full[:, ids], name="left_arm", to_matrix=False)
    assert pose7.shape == (2, 7)
    assert torch.allclose(pose7[:, :3], at_current_base[:, :3, 3])


def test_compute_ik_round_trip_through_robot(w1: object) -> None:
    solver = w1.get_solver("right_arm")
    q = sample_joint_values(solver.qpos_limits, 2, torch.Generator().manual_seed(5)).float()
    target = w1.compute_fk(q, name="right_arm")
    success, sol = w1.compute_ik(target, name="right_arm")
    assert sol.shape == (2, 7)
    assert success.dtype == torch.bool
    assert bool(success.all())
    reached = w1.compute_fk(sol, name="right_arm")
    assert torch.allclose(reached[:, :3, 3], target[:, :3, 3], atol=1e-3)


def test_compute_ik_env_subset_and_pose7(arm: object) -> None:
    current = arm.compute_fk(name="arm")
    target = current[1:].clone()
    target[:, 0, 3] += 0.05
    target[:, 2, 3] -= 0.05
    pose7 = torch.cat((target[:, :3, 3], torch.tensor([[0.0, 1.0, 0.0, 0.0]])), -1)  # gripper pointing down
    success, sol = arm.compute_ik(pose7, joint_seed=arm.get_qpos()[1:], name="arm", env_ids=[1])
    assert bool(success.all())
    assert sol.shape == (1, 7)
    arm.set_qpos(sol, joint_ids=arm.get_joint_ids("arm"), env_ids=[1], target=False)
    tcp = arm.compute_fk(name="arm", env_ids=[1])
    assert torch.allclose(tcp[0, :3, 3], pose7[0, :3], atol=1e-3)
    assert torch.allclose(tcp[0, :3, 2], torch.tensor([0.0, 0.0, -1.0]), atol=1e-3)
    arm.reset()


def test_solver_lookup_and_base_pose(w1: object, arm: object) -> None:
    assert arm.get_solver() is arm.solvers["arm"]
    assert w1.get_solver("left_arm").joint_ids == w1.get_joint_ids("left_arm")
    with pytest.raises(KeyError, match="left_eef"):
        w1.get_solver("left_eef")
    base = w1.get_control_part_base_pose("left_arm")
    assert torch.allclose(base[:, :3, 3], torch.tensor([0.0, 0.0985, 1.3648]).expand(2, 3), atol=1e-5)


def test_init_pos_moves_the_robot(scene_factory: object) -> None:
    robot = scene_factory(DexforceW1Cfg.from_dict({"uid": "w1", "init_pos": [0, 1, 0]}), num_envs=1)["w1"]
    ee = robot.get_link_pose("left_ee")[0]
    assert torch.allclose(ee[:3], torch.tensor([0.0, 1.791, 1.3648]), atol=1e-5)
    target = robot.compute_fk(name="left_arm")
    success, q = robot.compute_ik(target, name="left_arm")
    assert bool(success.all())
    assert float(q.abs().max()) < 1e-3


def test_fingers_close_and_pips_follow_in_simulation(scene_factory: object) -> None:
    robot = scene_factory(DexforceW1Cfg.from_dict({"uid": "w1"}), num_envs=1)["w1"]
    eef = robot.get_joint_ids("right_eef")
    robot.set_qpos(torch.full((1, len(eef)), 0.8), joint_ids=eef)
    for _ in range(50):
        assert robot.scene.sim.step(1) == []
    qpos = robot.get_qpos()[0]
    for finger in ("INDEX", "MIDDLE", "RING", "PINKY"):
        prox = qpos[robot.joint_names.index(f"RIGHT_HAND_{finger}")]
        pip = qpos[robot.joint_names.index(f"RIGHT_{finger}_PIP")]
        assert float(prox) == pytest.approx(0.8, abs=0.02)
        assert float(pip) == pytest.approx(float(prox), abs=0.02)
