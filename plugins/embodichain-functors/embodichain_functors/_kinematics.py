"""Robot kinematics through the robot's own solvers.

The functors call ``robot.compute_fk(name=part, to_matrix=True)`` and
``robot.compute_ik(pose (n, 4, 4), joint_seed=(n, k), name=part, env_ids=ids)
-> (success (n,), qpos (n, k))``; the solvers behind them come from the robot
config's ``build_solvers(robot)`` (robot plugins such as embodichain-robots).
``qpos`` is in the order of ``robot.get_solver(part).joint_ids``.

:func:`solve_ik_on_device` solves every env on the sim device without a host wait, for a
backend whose state is device memory (``sim.capabilities.host_arrays`` False: ``warp`` on a
GPU) and a solver with ``ik_on_device`` (embodichain-robots' ``DLSSolver``;
:func:`device_solver` finds it): the targets go to the part's root frame there, and the
solver runs a fixed number of iterations with no random restarts.
"""

from __future__ import annotations

from typing import Any, Optional

import torch

from embodichain_core.utils.math import pose_to_matrix, transform_inverse
from embodichain_functors._common import ParamError


def default_part(env: Any, robot: Any, part: Optional[str]) -> Optional[str]:
    """``part``, else the env's first control part, else the robot's first one."""
    if part:
        return part
    parts = list(getattr(env.cfg, "control_parts", None) or []) or list(getattr(robot, "control_parts", {}) or {})
    return parts[0] if parts else None


def check_part(robot: Any, part: Optional[str], functor: str, param: str) -> None:
    """``part`` must be a control part of ``robot`` (``None`` means the whole robot)."""
    if part is not None and part not in (getattr(robot, "control_parts", None) or {}):
        known = list(getattr(robot, "control_parts", None) or {})
        raise ParamError(functor, param, f"robot {robot.uid!r} has no control part {part!r} (parts: {known})")


def check_ik(robot: Any, part: Optional[str], functor: str, param: str) -> None:
    """The robot must have a kinematics solver for ``part`` (its config's ``build_solvers``)."""
    if not callable(getattr(robot, "compute_ik", None)):
        raise ParamError(functor, param, f"robot {robot.uid!r} has no inverse kinematics (compute_ik)")
    get_solver = getattr(robot, "get_solver", None)
    if callable(get_solver):
        try:
            get_solver(part)
        except KeyError as err:
            raise ParamError(
                functor,
                param,
                str(err).strip("\"'") + "; use a robot whose config builds kinematics solvers (embodichain-robots)",
            ) from None


def part_joints(robot: Any, part: Optional[str], width: Optional[int] = None) -> list[int]:
    """Joint ids solved for ``part`` (the solver's order); without a solver, the part's joints
    (those without mimic joints when ``width`` says so)."""
    get_solver = getattr(robot, "get_solver", None)
    if callable(get_solver):
        try:
            return [int(j) for j in get_solver(part).joint_ids]
        except (KeyError, AttributeError):
            pass
    joints = robot.get_joint_ids(part)
    if width is not None and len(joints) != width:
        joints = robot.get_joint_ids(part, remove_mimic=True)
    return joints


def eef_pose(robot: Any, part: Optional[str]) -> torch.Tensor:
    """(N, 4, 4) end-effector poses of ``part`` at the current joint positions."""
    return robot.compute_fk(name=part, to_matrix=True).to(torch.float32)


def device_solver(robot: Any, part: Optional[str]) -> Any:
    """``part``'s solver when IK runs on the sim device (see the module docstring), else None."""
    caps = getattr(getattr(robot, "sim", None), "capabilities", None)
    if caps is None or caps.host_arrays or not callable(getattr(robot, "get_solver", None)):
        return None
    solver = robot.get_solver(part)
    return solver if getattr(solver, "ik_on_device", False) else None


def solve_ik(
    robot: Any, pose: torch.Tensor, part: Optional[str], env_ids: torch.Tensor, seed: Optional[torch.Tensor] = None
) -> tuple[torch.Tensor, torch.Tensor, list[int]]:
    """IK for ``env_ids`` through ``robot.compute_ik``; failed envs keep the seed. Returns
    ``(success, qpos, joint ids)``."""
    joints = part_joints(robot, part)
    if seed is None:
        seed = robot.get_qpos()[env_ids][:, joints]
    success, qpos = robot.compute_ik(pose=pose, joint_seed=seed, name=part, env_ids=env_ids)
    success = torch.as_tensor(success, dtype=torch.bool).reshape(-1)
    qpos = torch.as_tensor(qpos, dtype=torch.float32).reshape(len(env_ids), -1)
    joints = part_joints(robot, part, qpos.shape[-1])
    if seed.shape[-1] != qpos.shape[-1]:
        seed = robot.get_qpos()[env_ids][:, joints]
    qpos = torch.where(success[:, None], qpos, seed.to(qpos.dtype))
    return success, qpos, joints


def solve_ik_on_device(
    robot: Any, solver: Any, pose: torch.Tensor, part: Optional[str], seed: Optional[torch.Tensor] = None
) -> tuple[torch.Tensor, torch.Tensor, list[int]]:
    """IK of every env on the sim device with no host wait: ``pose`` (N, 4, 4) env-frame
    targets to the root link frame of ``part``, ``solver.get_ik_on_device`` from ``seed``
    (default: the current joint positions), failed envs kept at the seed.

    Returns:
        ``(success (N,) bool, qpos (N, k) float32, joint ids)`` on the sim device.
    """
    joints = [int(j) for j in solver.joint_ids]
    if seed is None:  # an index list: a host copy (callers in the step pass the seed)
        seed = robot.get_qpos()[:, joints]
    base = robot.get_control_part_base_pose(part, to_matrix=False).to(torch.float64)
    local = transform_inverse(pose_to_matrix(base)) @ pose.to(torch.float64)
    success, qpos = solver.get_ik_on_device(local, seed)
    qpos = qpos.to(torch.float32)
    return success, torch.where(success[:, None], qpos, seed.to(qpos.dtype)), joints
