"""Batched kinematics: chain FK/Jacobian against MuJoCo, IK round trips, limits."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import torch

from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg
from embodichain_robots.kinematics.chain import SerialChain
from embodichain_robots.kinematics.mj_solver import MjDLSSolver
from embodichain_robots.kinematics.solver import DLSSolver, IKSolverCfg, sample_joint_values
from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg


def random_qpos(limits: torch.Tensor, n: int, seed: int) -> torch.Tensor:
    return sample_joint_values(limits, n, torch.Generator().manual_seed(seed))


CASES = {
    "w1_left": (DexforceW1Cfg, "left_arm"),
    "w1_right": (DexforceW1Cfg, "right_arm"),
    "w1_industrial_left": (lambda: DexforceW1Cfg(arm_kind="industrial"), "left_arm"),
    "arm": (SevenDofArmCfg, "arm"),
}


def _solver(case: str, cls: type = DLSSolver) -> tuple[DLSSolver, mujoco.MjModel]:
    make, part = CASES[case]
    cfg = make()
    model = cfg.build_spec().compile()
    return cls.from_model(cfg.solver_cfg[part], model), model


@pytest.mark.parametrize("case", sorted(CASES))
def test_chain_fk_and_jacobian_match_mujoco(case: str) -> None:
    solver, model = _solver(case)
    reference, _ = _solver(case, MjDLSSolver)
    q = random_qpos(solver.qpos_limits, 20, seed=1)
    pose, jac = solver.fk_jacobian(q)
    ref_pose, ref_jac = reference.fk_jacobian(q)
    assert torch.allclose(pose, ref_pose, atol=1e-10)
    assert torch.allclose(jac, ref_jac, atol=1e-9)


def test_chain_handles_slides_and_offset_anchors() -> None:
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="a")
    b1 = body.add_body(name="b", pos=[0.1, 0.2, 0.3], quat=[0.9, 0.1, 0.3, 0.2])
    b1.add_joint(name="j1", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[1, 1, 0], pos=[0.05, 0, 0.02])
    b1.add_joint(name="j2", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 1])
    b1.add_geom(size=[0.05, 0, 0])
    tip = b1.add_body(name="c", pos=[0, 0, 0.2])
    tip.add_joint(name="j3", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], pos=[0.01, 0.02, 0])
    tip.add_geom(size=[0.05, 0, 0])
    model = spec.compile()
    chain = SerialChain.from_model(model, "a", "c")
    data = mujoco.MjData(model)
    q = torch.tensor([[0.3, 0.1, -0.7], [1.2, -0.05, 2.0]], dtype=torch.float64)
    for k in range(2):
        data.qpos[:] = q[k].numpy()
        mujoco.mj_kinematics(model, data)
        expected = np.eye(4)
        expected[:3, :3], expected[:3, 3] = data.xmat[model.body("c").id].reshape(3, 3), data.xpos[model.body("c").id]
        assert np.allclose(chain.fk(q)[k].numpy(), expected, atol=1e-12)


@pytest.mark.parametrize("case", sorted(CASES))
def test_ik_round_trip(case: str) -> None:
    """FK(IK(FK(q))) within 1 mm / 0.01 rad on >= 95 % of random reachable targets."""
    solver, _ = _solver(case)
    limits = solver.qpos_limits
    target = solver.get_fk(random_qpos(limits, 120, seed=2))
    seed = torch.zeros(120, solver.dof, dtype=torch.float64).clamp(limits[:, 0], limits[:, 1])
    success, q = solver.get_ik(target, qpos_seed=seed)
    pos_err, rot_err = solver.pose_error(target, q)
    good = (pos_err < 1e-3) & (rot_err < 0.01)
    assert good.float().mean() >= 0.95
    assert bool((good | ~success).all())  # success implies accuracy
    assert bool(((q >= limits[:, 0]) & (q <= limits[:, 1])).all())


def test_ik_near_seed_is_fast_and_exact() -> None:
    solver, _ = _solver("w1_left")
    q = random_qpos(solver.qpos_limits, 64, seed=3)
    target = solver.get_fk(q)
    nudged = (q + 0.05).clamp(solver.qpos_limits[:, 0], solver.qpos_limits[:, 1])
    success, sol = solver.get_ik(target, qpos_seed=nudged, num_restarts=0)
    assert bool(success.all())
    pos_err, rot_err = solver.pose_error(target, sol)
    assert float(pos_err.max()) < 1e-4
    assert float(rot_err.max()) < 1e-3


def test_unreachable_target_fails_and_stays_in_limits() -> None:
    solver, _ = _solver("arm")
    target = torch.eye(4, dtype=torch.float64).repeat(3, 1, 1)
    target[:, 0, 3] = torch.tensor([2.0, 0.0, 0.3])  # 2 m away, beyond reach
    success, q = solver.get_ik(target, num_restarts=1)
    assert not bool(success[0])
    limits = solver.qpos_limits
    assert bool(((q >= limits[:, 0]) & (q <= limits[:, 1])).all())


@pytest.mark.parametrize("case", ["w1_left", "arm"])
def test_ik_on_device_is_the_first_attempt_of_get_ik(case: str) -> None:
    """``get_ik_on_device`` (fixed iteration count, no host read, no restarts) returns what
    ``get_ik`` without restarts returns: the same success flags and joint values, for targets
    near the seed (solved), far from it (most not solved in 20 iterations) and out of reach."""
    solver, _ = _solver(case)
    limits = solver.qpos_limits
    start = random_qpos(limits, 48, seed=5)
    goal = start.clone()
    goal[:16] += 0.05  # near
    goal[16:40] = random_qpos(limits, 24, seed=6)  # far
    target = solver.get_fk(goal.clamp(limits[:, 0], limits[:, 1]))
    target[40:, 0, 3] += 3.0  # beyond reach
    ok_host, q_host = solver.get_ik(target, qpos_seed=start, num_restarts=0)
    ok_dev, q_dev = solver.get_ik_on_device(target, start)
    assert bool(ok_host[:16].all())
    assert not bool(ok_host[40:].any())
    assert 0 < int(ok_host[16:40].sum()) < 24  # both outcomes among the far targets
    assert torch.equal(ok_dev, ok_host)
    assert torch.equal(q_dev, q_host)  # converged envs stand still through the remaining iterations
    assert solver.ik_on_device
    assert not MjDLSSolver.ik_on_device


def test_mujoco_reference_solver_agrees() -> None:
    solver, _ = _solver("arm", MjDLSSolver)
    target = solver.get_fk(random_qpos(solver.qpos_limits, 8, seed=4))
    success, q = solver.get_ik(target, qpos_seed=torch.tensor([0.0, -0.785, 0, -2.356, 0, 1.571, 0.785]).repeat(8, 1))
    pos_err, _ = solver.pose_error(target, q)
    assert success.float().mean() >= 0.75
    assert float(pos_err[success].max()) < 1e-3


def test_solver_tcp_api() -> None:
    solver, _ = _solver("arm")
    tcp = solver.get_tcp()
    moved = tcp.clone()
    moved[2, 3] += 0.1
    solver.set_tcp(moved)
    q = torch.zeros(1, 7, dtype=torch.float64)
    shift = solver.get_fk(q)[0, :3, 3]
    solver.set_tcp(tcp)
    assert torch.allclose(shift - solver.get_fk(q)[0, :3, 3], solver.get_fk(q)[0, :3, 2] * 0.1, atol=1e-12)
    assert IKSolverCfg().class_type == "DLSSolver"
