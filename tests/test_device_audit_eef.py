"""End-effector pose actions (``EefPoseTerm``) on the ``warp`` backend's device paths: host
waits per env step counted by the device audit
(:class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit`) on Warp's CPU device, and
the device IK against the CPU IK it replaces there.

On the device route the term solves on the sim device (``DLSSolver.get_ik_on_device``: a fixed
number of iterations, converged envs masked, no random restarts), so the step waits for the
device only for the done flags, as with joint actions (tests/test_device_audit.py).
"""

from __future__ import annotations

from typing import Any, Iterator

import pytest
import torch

from core_testlib import audited_push_cube

from embodichain_core.sim.backend.device_audit import HostWaitAudit
from embodichain_core.utils.math import matrix_to_pose, pose_to_matrix

#: The most host waits an env step with an EefPoseTerm action may make on the device route.
WAIT_BUDGET = 2
STEPS = 4
PART = "arm"


@pytest.fixture(scope="module")
def audited() -> Iterator[tuple[Any, HostWaitAudit]]:
    """PushCube-v1 with an ``EefPoseTerm`` action instead of joint deltas, on backend warp
    (Warp's CPU device, 2 envs), built and reset inside the audit (so on the device paths)."""
    import embodichain_functors.actions as actions
    from embodichain_core.managers import ActionTermCfg

    yield from audited_push_cube({"eef": ActionTermCfg(func=actions.EefPoseTerm, params={"part_name": PART})})


def _targets(env: Any, shift: tuple[float, float, float], yaw: float = 0.0) -> torch.Tensor:
    """(N, 7) TCP targets in the env frame: the current TCP pose moved by ``shift`` (metres)
    and turned by ``yaw`` (radians about the env's z axis, in place)."""
    pose = env.robot.compute_fk(name=PART, to_matrix=True).to(torch.float64)
    c, s = torch.cos(torch.tensor(yaw)), torch.sin(torch.tensor(yaw))
    turn = torch.eye(4, dtype=torch.float64)
    turn[:2, :2] = torch.stack((torch.stack((c, -s)), torch.stack((s, c))))
    pose[:, :3, :3] = turn[:3, :3].to(pose.device) @ pose[:, :3, :3]
    pose[:, :3, 3] += torch.tensor(shift, dtype=torch.float64, device=pose.device)
    return matrix_to_pose(pose).to(torch.float32)


def test_an_eef_pose_step_waits_for_the_device_at_most_twice(audited: tuple) -> None:
    env, audit = audited
    HostWaitAudit.check_env(env)
    term = env.action_manager.terms()["eef"]
    assert term._solver is not None, "the term did not take the device IK on the device route"
    action = _targets(env, (0.02, 0.0, -0.02))
    env.step(action)  # first-step work (lazy caches) stays out of the count
    audit.clear()
    for _ in range(STEPS):
        env.step(action)
    report = audit.per_step(STEPS)
    sites = "\n".join(f"{s['per_step']:.2f} {s['kind']}: {s['site']}" for s in report["sites"])
    assert report["per_step"] <= WAIT_BUDGET, f"{report['per_step']} host waits per step:\n{sites}"
    assert report["per_step"] >= 1, "the done flags are read every step: the audit counted nothing"
    assert not report["mixed"], f"ops that raise on CUDA: {report['mixed']}"
    command = term.process_action(action)
    assert bool(command["ik_success"].all())


@pytest.mark.parametrize(
    "shift, yaw, solved",
    [
        ((0.02, 0.0, -0.02), 0.0, [True, True]),
        ((-0.03, 0.04, 0.05), 0.3, [True, True]),
        ((3.0, 0.0, 0.0), 0.0, [False, False]),  # out of reach: both keep their joints
    ],
)
def test_the_device_ik_matches_the_cpu_ik(audited: tuple, shift: tuple, yaw: float, solved: list) -> None:
    """The same success flags and joint targets as ``robot.compute_ik`` on the CPU (the path
    the term takes on a backend with host arrays), from the same state and seed."""
    from embodichain_functors._kinematics import device_solver, solve_ik, solve_ik_on_device

    env, _ = audited
    robot = env.robot
    solver = device_solver(robot, PART)
    pose = pose_to_matrix(_targets(env, shift, yaw).to(torch.float64)).to(torch.float32)
    seed = robot.get_qpos()[:, list(solver.joint_ids)]
    ok_dev, q_dev, joints = solve_ik_on_device(robot, solver, pose, PART, seed)
    ok_cpu, q_cpu, joints_cpu = solve_ik(robot, pose, PART, torch.arange(env.num_envs), seed)
    assert joints == joints_cpu
    assert ok_dev.tolist() == ok_cpu.tolist() == solved
    assert q_dev.device == env.device
    assert q_dev.dtype == q_cpu.dtype == torch.float32
    assert torch.allclose(q_dev.cpu(), q_cpu.cpu(), atol=1e-5)
    if not any(solved):
        assert torch.equal(q_dev, seed)


def test_compute_ik_on_the_device_route_restarts_on_the_cpu_what_the_device_left(audited: tuple) -> None:
    """``robot.compute_ik``'s device route (``part_ik``): the device solves, the envs it left
    unsolved get ``get_ik``'s restarts on the CPU, and the result is ``get_ik``'s exactly;
    a solve where every env converges waits for the device once."""
    from embodichain_core.sim.entities.part_ik import solve_part_ik

    env, audit = audited
    solver = env.robot.get_solver(PART)
    limits = solver.chain.limits
    goal = limits[:, 0] + (limits[:, 1] - limits[:, 0]) * torch.rand(
        16, len(limits), generator=torch.Generator().manual_seed(0), dtype=torch.float64
    )
    target = solver.get_fk(goal)
    seed = ((limits[:, 0] + limits[:, 1]) / 2).expand(16, -1).clone()
    first, _ = solver.get_ik_on_device(target, seed)
    assert first.any(), "some envs must converge on the device"
    assert not first.all(), "some envs must need the CPU's restarts"
    ok_host, q_host = solve_part_ik(solver, target, seed, on_device=False)
    ok_route, q_route = solve_part_ik(solver, target, seed, on_device=True)
    assert torch.equal(ok_route, ok_host)
    assert bool(ok_host.all())
    assert torch.equal(q_route, q_host)
    converged = (target[first].clone(), seed[first].clone())
    audit.mark_device(*converged)  # as a GPU run hands them over
    audit.clear()
    solve_part_ik(solver, *converged, on_device=True)
    report = audit.per_step(1)
    assert report["by_kind"] == {"nonzero": 1.0}, report["sites"]
    assert "part_ik.py" in report["sites"][0]["site"]
