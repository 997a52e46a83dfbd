"""End-effector pose action term: a TCP pose target solved to joint targets by IK."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from embodichain_core.utils.math import euler_xyz_to_quat, pose_to_matrix, quat_to_euler_xyz

from embodichain_functors._common import ParamError
from embodichain_functors._kinematics import (
    check_ik,
    default_part,
    device_solver,
    part_joints,
    solve_ik,
    solve_ik_on_device,
)
from embodichain_functors.actions.base import _Term


class EefPoseTerm(_Term):
    """An end-effector pose target solved to joint targets by the robot's batched IK.

    The action is 7D (xyz + quaternion wxyz) or 6D (xyz + extrinsic xyz Euler angles
    in radians), in the env frame; ``scale`` scales the position. With ``gripper_part``
    the action goes on with that part's joint position targets (a hand or gripper: pose,
    then one value per joint of the part). Envs whose IK fails keep their current joint
    positions. Returns ``{"qpos": (N, n_active), "ik_success": (N,) bool}``; active joints
    outside the two parts hold their targets.

    A scripted demonstration written as joint targets is recorded in this action space
    through :meth:`action_from_qpos` (the TCP pose of the targets by forward kinematics).
    Its quaternions are written in the hemisphere of the TCP's orientation at the robot's
    default joint positions, so a recorded action varies continuously (``q`` and ``-q`` are
    the same rotation, and a top-down grasp sits where ``w`` changes sign).

    On a backend whose state is device memory (``warp`` on a GPU) with a solver that solves
    on the device (``DLSSolver``), the IK runs there with no host wait: a fixed number of
    iterations and no random restarts (docs/performance.md, "Device audit"). Elsewhere it runs
    through ``robot.compute_ik`` on the CPU, restarts included.

    **Execution noise** (for recording demonstrations, in the style of DART): with ``noise_std``
    (metres) above 0 the TCP position the IK solves for is the action's plus an offset that
    wanders per env (an Ornstein-Uhlenbeck process with time constant ``noise_tau`` steps and
    standard deviation ``noise_std``), during the first ``noise_steps`` steps of each episode
    (every step when None), after which it is gone. The action itself, which a recorder keeps,
    stays clean: the data then holds states off the plan labelled with the plan's absolute
    target. The draws come from the env's per-episode random streams, so an episode replays
    exactly from its seed and its recorded actions.

    Params: ``scale`` (1.0), ``pose_dim`` (7), ``part_name`` (the env's first control part),
    ``gripper_part`` (None), ``noise_std`` (0.0), ``noise_tau`` (10.0), ``noise_steps`` (None).

    Example:
        ``{"func": "EefPoseTerm", "params": {"part_name": "right_arm", "gripper_part": "right_eef"}}``
    """

    input_key = "eef_pose"
    defaults = {
        "scale": 1.0,
        "pose_dim": 7,
        "part_name": None,
        "gripper_part": None,
        "noise_std": 0.0,
        "noise_tau": 10.0,
        "noise_steps": None,
    }

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        if self.params["pose_dim"] not in (6, 7):
            raise ValueError(f"params.pose_dim: EEF pose action must be 6D or 7D, got {self.params['pose_dim']!r}")
        self.pose_dim = int(self.params["pose_dim"])
        self.part = default_part(env, self.robot, self.params["part_name"])
        if self.part is not None and self.part not in (self.robot.control_parts or {}):
            raise ValueError(f"params.part_name: robot {self.robot.uid!r} has no control part {self.part!r}")
        try:
            check_ik(self.robot, self.part, type(self).__name__, "part_name")
        except ParamError as err:
            raise ValueError(f"params.part_name: {err.reason.split(': ', 1)[-1]}") from None
        self._gripper = self._gripper_columns(self.params["gripper_part"]).to(self._joints.device)
        self._part_joints = part_joints(self.robot, self.part)  # the part's joints, in the solver's order
        self._all = torch.arange(env.num_envs)
        self._solver = device_solver(self.robot, self.part)
        if self._solver is not None:  # the part's joints in the solver's order, on the device
            self._seed_cols = torch.as_tensor(self._solver.joint_ids, dtype=torch.long, device=env.device)
        self._scatter: dict[tuple[int, ...], tuple[torch.Tensor, torch.Tensor]] = {}
        self._reference: torch.Tensor | None = None
        self._noise = _ExecutionNoise(env, self.params) if self.params["noise_std"] else None

    def reset(self, env_ids: Any = None) -> None:
        super().reset(env_ids)
        if self._noise is not None:
            self._noise.reset(env_ids)

    def _gripper_columns(self, part: Any) -> torch.Tensor:
        """Columns of the active joints that ``gripper_part``'s joints (mimic ones left out) fill."""
        if part is None:
            return torch.zeros(0, dtype=torch.long)
        parts = list(self.robot.control_parts or {})
        if part not in parts or part == self.part:
            choices = [p for p in parts if p != self.part]
            raise ValueError(
                f"params.gripper_part: {part!r} is not a control part of robot {self.robot.uid!r} "
                f"other than part_name {self.part!r} (parts: {choices})"
            )
        joints, active = self.robot.get_joint_ids(part, remove_mimic=True), self.joints.tolist()
        missing = [str(self.robot.joint_names[j]) for j in joints if j not in active]
        if missing:
            raise ValueError(
                f"params.gripper_part: joints {missing} of {part!r} are not active joints of the env; "
                f"add {part!r} to control_parts"
            )
        return torch.as_tensor([active.index(j) for j in joints], dtype=torch.long)

    @property
    def action_dim(self) -> int:
        return self.pose_dim + len(self._gripper)

    def action_names(self) -> list[str]:
        axes = ["x", "y", "z", "qw", "qx", "qy", "qz"] if self.pose_dim == 7 else ["x", "y", "z", "rx", "ry", "rz"]
        joints = [str(self.robot.joint_names[int(self.joints[c])]) for c in self._gripper.tolist()]
        return [f"{self.part}.{a}" for a in axes] + joints

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        high = torch.full((self.pose_dim,), float("inf"))
        if self.pose_dim == 7:
            high[3:] = 1.0
        limits = self.limits()[0][self._gripper].float().cpu()
        return torch.cat((-high, limits[:, 0])), torch.cat((high, limits[:, 1]))

    def target_pose(self, action: torch.Tensor) -> torch.Tensor:
        """(N, 4, 4) targets of an (N, 6|7) pose action."""
        action = torch.as_tensor(action, dtype=torch.float64)
        if action.dim() != 2 or action.shape[-1] not in (6, 7):
            raise ValueError(f"EEF pose action must be 6D or 7D, got shape {tuple(action.shape)}")
        if action.shape[-1] == 6:
            quat = euler_xyz_to_quat(action[:, 3:], degrees=False)
        else:
            quat = action[:, 3:] / action[:, 3:].norm(dim=-1, keepdim=True).clamp_min(1e-12)
        return pose_to_matrix(torch.cat((self.scale * action[:, :3], quat), -1)).float()

    def process_action(self, action: torch.Tensor) -> dict[str, torch.Tensor]:
        action = torch.as_tensor(action, dtype=torch.float32)
        if action.dim() != 2 or action.shape[-1] != self.action_dim:
            raise ValueError(
                f"{type(self).__name__} takes {self.action_dim} values per env (a {self.pose_dim}D pose, 6D or 7D, "
                f"then {len(self._gripper)} gripper joint targets), got shape {tuple(action.shape)}"
            )
        pose = self.target_pose(action[:, : self.pose_dim])
        if self._noise is not None:
            pose[:, :3, 3] += self._noise.step().to(pose)
        if self._solver is not None:
            seed = self.robot.get_qpos()[:, self._seed_cols]
            success, qpos, joints = solve_ik_on_device(self.robot, self._solver, pose, self.part, seed)
        else:
            success, qpos, joints = solve_ik(self.robot, pose, self.part, self._all)
        command = self.robot.get_qpos(target=True)[:, self._joints].clone()
        columns, solved = self._columns_of(joints)
        command[:, columns] = qpos[:, solved]
        if len(self._gripper):
            command[:, self._gripper] = action[:, self.pose_dim :].to(command)
        return {"qpos": command, "ik_success": success}

    def action_from_qpos(self, qpos: torch.Tensor) -> torch.Tensor:
        """The action of (N, n_active) joint targets ``qpos``: the part's TCP pose at them
        (forward kinematics; position divided by ``scale``), then the gripper's targets."""
        qpos = torch.as_tensor(qpos, dtype=torch.float64).to(self._joints.device)
        pose = self._tcp_pose(qpos)
        quat = pose[:, 3:] * torch.where((pose[:, 3:] * self._quat_reference()).sum(-1, keepdim=True) < 0, -1.0, 1.0)
        rotation = quat if self.pose_dim == 7 else quat_to_euler_xyz(quat, degrees=False)
        return torch.cat((pose[:, :3] / self.scale, rotation, qpos[:, self._gripper]), -1).float()

    def _tcp_pose(self, qpos: torch.Tensor) -> torch.Tensor:
        """(N, 7) TCP poses of ``part`` at active-joint targets ``qpos`` (other joints of the
        part at their current targets)."""
        part_q = self.robot.get_qpos(target=True)[:, self._part_joints].to(torch.float64).clone()
        columns, solved = self._columns_of(self._part_joints)
        part_q[:, solved] = qpos[:, columns]
        return self.robot.compute_fk(qpos=part_q, name=self.part, to_matrix=False).to(torch.float64)

    def _quat_reference(self) -> torch.Tensor:
        """(N, 4) TCP orientation at the robot's default joint positions (computed once)."""
        if self._reference is None:
            joints = self._part_joints
            default = self.robot.default_qpos[joints].to(torch.float64).expand(self.num_envs, len(joints))
            self._reference = self.robot.compute_fk(qpos=default, name=self.part, to_matrix=False)[:, 3:].to(
                torch.float64
            )
        return self._reference

    def _columns_of(self, joints: list[int]) -> tuple[torch.Tensor, torch.Tensor]:
        """``(columns of the active joints, columns of qpos)`` for the solved ``joints`` that
        are active, as index tensors on the env's device (made once per joint list)."""
        key = tuple(joints)
        if key not in self._scatter:
            active = self.joints.tolist()
            pairs = [(active.index(j), k) for k, j in enumerate(joints) if j in active]
            device = self._joints.device
            self._scatter[key] = (
                torch.as_tensor([a for a, _ in pairs], dtype=torch.long, device=device),
                torch.as_tensor([k for _, k in pairs], dtype=torch.long, device=device),
            )
        return self._scatter[key]


class _ExecutionNoise:
    """Per-env TCP position offsets of :class:`EefPoseTerm`'s ``noise_*`` params."""

    def __init__(self, env: Any, params: dict):
        std, tau, steps = params["noise_std"], params["noise_tau"], params["noise_steps"]
        for name, value, low in (("noise_std", std, 0.0), ("noise_tau", tau, 0.0)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > low:
                raise ValueError(f"params.{name}: a number above {low:g}, got {value!r}")
        if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int) or steps < 1):
            raise ValueError(f"params.noise_steps: a whole number of steps, at least 1 (or null), got {steps!r}")
        self.env, self.std, self.steps = env, float(std), steps
        self.decay = math.exp(-1.0 / float(tau))
        self.offset = torch.zeros(env.num_envs, 3, dtype=torch.float64)
        self.age = torch.zeros(env.num_envs, dtype=torch.long)

    def reset(self, env_ids: Any = None) -> None:
        ids = slice(None) if env_ids is None else torch.as_tensor(env_ids, dtype=torch.long).cpu()
        self.offset[ids] = 0.0
        self.age[ids] = 0

    def step(self) -> torch.Tensor:
        """(N, 3) offsets of this step (zero past ``noise_steps``)."""
        draw = torch.as_tensor(self.env.rng.normal(np.arange(self.env.num_envs), shape=(3,)))
        self.offset = self.decay * self.offset + math.sqrt(1.0 - self.decay**2) * self.std * draw
        if self.steps is not None:
            self.offset[self.age >= self.steps] = 0.0
        self.age += 1
        return self.offset
