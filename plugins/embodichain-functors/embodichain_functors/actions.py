"""Action terms: turn the policy action into robot commands (``ActionTermCfg(func=...)``).

Every term acts on the env's active joints (``control_parts`` or
``active_joint_ids``; mimic joints follow their parents) and returns commands of
that width. ``QvelTerm`` and ``QfTerm`` really drive velocity and effort: the
action manager routes their output by ``input_key`` to the velocity drives and to
the applied joint forces.

Example:
    >>> import embodichain_functors.actions as actions
    >>> ActionTermCfg(func=actions.DeltaQposTerm, params={"scale": 0.1})
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_core.managers.functor import ActionTerm
from embodichain_core.utils.math import euler_xyz_to_quat, pose_to_matrix

from embodichain_functors._common import ParamError
from embodichain_functors._kinematics import check_ik, default_part, device_solver, solve_ik, solve_ik_on_device

__all__ = [
    "DeltaQposTerm",
    "QposTerm",
    "QposDenormalizedTerm",
    "QposNormalizedTerm",
    "EefPoseTerm",
    "QvelTerm",
    "QfTerm",
    "DEFAULT_QVEL_LIMIT",
    "DEFAULT_QF_LIMIT",
]


class _Term(ActionTerm):
    """Params with defaults (``defaults``); unknown params are errors at construction."""

    defaults: dict[str, Any] = {"scale": 1.0}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        unknown = [k for k in cfg.params if k not in self.defaults]
        if unknown:
            raise ValueError(
                f"params.{unknown[0]}: unknown parameter of {type(self).__name__} (parameters: {sorted(self.defaults)})"
            )
        self.params = {**self.defaults, **cfg.params}
        scale = self.params.get("scale", 1.0)
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or scale == 0:
            raise ValueError(f"params.scale: must be a non-zero number, got {scale!r}")
        self.scale = float(scale)
        self.robot = env.robot
        self.joints = torch.as_tensor(env.active_joint_ids, dtype=torch.long)
        self._joints = self.joints.to(env.device, copy=True)  # the same, on the env's device
        self._limits: torch.Tensor | None = None

    def limits(self) -> torch.Tensor:
        """(N, n_active, 2) position limits of the active joints, on the env's device; read
        once and again after every reset (reset events may randomize them)."""
        if self._limits is None:
            self._limits = self.robot.get_qpos_limits()[:, self._joints]
        return self._limits

    def reset(self, env_ids: Any = None) -> None:
        """Read the joint limits again at the next :meth:`limits` (after the reset events)."""
        self._limits = None

    def _columns(self, key: str = "joint_ids") -> torch.Tensor:
        ids = self.params.get(key)
        n = len(self.joints)
        cols = torch.arange(n) if ids is None else torch.as_tensor(ids, dtype=torch.long).reshape(-1)
        if len(cols) and (cols.min() < 0 or cols.max() >= n):
            raise ValueError(f"params.{key}: indices into the {n} active joints, got {cols.tolist()}")
        return cols

    def _range(self, default: tuple) -> tuple[float, float]:
        rng = self.params.get("range", default)
        if not isinstance(rng, (list, tuple)) or len(rng) != 2 or float(rng[0]) >= float(rng[1]):
            raise ValueError(f"params.range: expected [low, high] with low < high, got {rng!r}")
        return float(rng[0]), float(rng[1])


class DeltaQposTerm(_Term):
    """Joint position targets = current positions of the active joints + ``scale * action``.

    Works with any subset of active joints. The policy range is
    ``[-action_limit, action_limit]`` per joint; targets are clipped to the joint
    limits (``clip=True``).

    Params: ``scale`` (1.0), ``action_limit`` (1.0), ``clip`` (True).

    Example:
        ``{"func": "DeltaQposTerm", "params": {"scale": 0.1}}``
    """

    input_key = "qpos"
    defaults = {"scale": 1.0, "action_limit": 1.0, "clip": True}

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        limit = float(self.params["action_limit"])
        return torch.full((self.action_dim,), -limit), torch.full((self.action_dim,), limit)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        target = self.robot.get_qpos()[:, self._joints] + self.scale * torch.as_tensor(action, dtype=torch.float32)
        if self.params["clip"]:
            lim = self.limits()
            target = torch.maximum(torch.minimum(target, lim[..., 1]), lim[..., 0])
        return target


class QposTerm(_Term):
    """Joint position targets = ``scale * action`` (policy range: the joint limits / scale).

    Params: ``scale`` (1.0).

    Example:
        ``{"func": "QposTerm", "params": {"scale": 1.0}}``
    """

    input_key = "qpos"

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0] / self.scale
        return lim.min(-1).values, lim.max(-1).values

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return self.scale * torch.as_tensor(action, dtype=torch.float32)


class QposDenormalizedTerm(_Term):
    """Map ``scale * action`` from ``range`` to the joint limits for ``joint_ids``.

    Other active joints take ``scale * action`` as is.

    Params: ``scale`` (1.0), ``joint_ids`` (indices into the active joints; all), ``range`` ([-1, 1]).

    Example:
        ``{"func": "QposDenormalizedTerm", "params": {"range": [-1, 1]}}``
    """

    input_key = "qpos"
    defaults = {"scale": 1.0, "joint_ids": None, "range": (-1.0, 1.0)}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.cols, self.range = self._columns(), self._range((-1.0, 1.0))

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0] / self.scale
        low, high = lim.min(-1).values, lim.max(-1).values
        low[self.cols], high[self.cols] = self.range[0] / self.scale, self.range[1] / self.scale
        return low, high

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = self.scale * torch.as_tensor(action, dtype=torch.float32)
        lim = self.limits()[:, self.cols]
        r0, r1 = self.range
        out[:, self.cols] = lim[..., 0] + (out[:, self.cols] - r0) / (r1 - r0) * (lim[..., 1] - lim[..., 0])
        return out


class QposNormalizedTerm(_Term):
    """Map joint positions from the joint limits to ``range`` for ``joint_ids`` (usually ``mode="post"``).

    Params: ``joint_ids`` (indices into the active joints; all), ``range`` ([0, 1]).

    Example:
        ``{"func": "QposNormalizedTerm", "mode": "post", "params": {"range": [0, 1]}}``
    """

    input_key = "qpos"
    defaults = {"joint_ids": None, "range": (0.0, 1.0)}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.cols, self.range = self._columns(), self._range((0.0, 1.0))

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        lim = self.limits()[0]
        return lim[:, 0], lim[:, 1]

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = torch.as_tensor(action, dtype=torch.float32).clone()
        lim = self.limits()[:, self.cols]
        r0, r1 = self.range
        span = (lim[..., 1] - lim[..., 0]).clamp_min(1e-12)
        out[:, self.cols] = r0 + (out[:, self.cols] - lim[..., 0]) / span * (r1 - r0)
        return out


class EefPoseTerm(_Term):
    """An end-effector pose target solved to joint targets by the robot's batched IK.

    The action is 7D (xyz + quaternion wxyz) or 6D (xyz + extrinsic xyz Euler angles
    in radians), in the env frame; ``scale`` scales the position. Envs whose IK
    fails keep their current joint positions. Returns ``{"qpos": (N, n_active),
    "ik_success": (N,) bool}``; active joints outside the part hold their targets.

    On a backend whose state is device memory (``warp`` on a GPU) with a solver that solves
    on the device (``DLSSolver``), the IK runs there with no host wait: a fixed number of
    iterations and no random restarts (docs/performance.md, "Device audit"). Elsewhere it runs
    through ``robot.compute_ik`` on the CPU, restarts included.

    Params: ``scale`` (1.0), ``pose_dim`` (7), ``part_name`` (the env's first control part).

    Example:
        ``{"func": "EefPoseTerm", "params": {"pose_dim": 7, "part_name": "arm"}}``
    """

    input_key = "eef_pose"
    defaults = {"scale": 1.0, "pose_dim": 7, "part_name": None}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        if self.params["pose_dim"] not in (6, 7):
            raise ValueError(f"params.pose_dim: EEF pose action must be 6D or 7D, got {self.params['pose_dim']!r}")
        self.part = default_part(env, self.robot, self.params["part_name"])
        if self.part is not None and self.part not in (self.robot.control_parts or {}):
            raise ValueError(f"params.part_name: robot {self.robot.uid!r} has no control part {self.part!r}")
        try:
            check_ik(self.robot, self.part, type(self).__name__, "part_name")
        except ParamError as err:
            raise ValueError(f"params.part_name: {err.reason.split(': ', 1)[-1]}") from None
        self._all = torch.arange(env.num_envs)
        self._solver = device_solver(self.robot, self.part)
        if self._solver is not None:  # the part's joints in the solver's order, on the device
            self._seed_cols = torch.as_tensor(self._solver.joint_ids, dtype=torch.long, device=env.device)
        self._scatter: dict[tuple[int, ...], tuple[torch.Tensor, torch.Tensor]] = {}

    @property
    def action_dim(self) -> int:
        return int(self.params["pose_dim"])

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        high = torch.full((self.action_dim,), float("inf"))
        if self.action_dim == 7:
            high[3:] = 1.0
        return -high, high

    def target_pose(self, action: torch.Tensor) -> torch.Tensor:
        """(N, 4, 4) targets of an (N, 6|7) action."""
        action = torch.as_tensor(action, dtype=torch.float64)
        if action.dim() != 2 or action.shape[-1] not in (6, 7):
            raise ValueError(f"EEF pose action must be 6D or 7D, got shape {tuple(action.shape)}")
        if action.shape[-1] == 6:
            quat = euler_xyz_to_quat(action[:, 3:], degrees=False)
        else:
            quat = action[:, 3:] / action[:, 3:].norm(dim=-1, keepdim=True).clamp_min(1e-12)
        return pose_to_matrix(torch.cat((self.scale * action[:, :3], quat), -1)).float()

    def process_action(self, action: torch.Tensor) -> dict[str, torch.Tensor]:
        pose = self.target_pose(action)
        if self._solver is not None:
            seed = self.robot.get_qpos()[:, self._seed_cols]
            success, qpos, joints = solve_ik_on_device(self.robot, self._solver, pose, self.part, seed)
        else:
            success, qpos, joints = solve_ik(self.robot, pose, self.part, self._all)
        command = self.robot.get_qpos(target=True)[:, self._joints].clone()
        columns, solved = self._columns_of(joints)
        command[:, columns] = qpos[:, solved]
        return {"qpos": command, "ik_success": success}

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


def _disable_drive(term: _Term, **gains: float) -> None:
    """Set drive gains of the active driven joints in every env."""
    driven = [int(j) for j in term.joints if int(term.robot.pos_act[j]) >= 0]
    if driven:
        term.robot.set_joint_drive(**gains, joint_ids=driven)


#: Velocity bound of a joint that declares none: rad/s for hinges, m/s for slides
#: (set ``drive_pros.max_velocity`` on the robot to use the real limits).
DEFAULT_QVEL_LIMIT: dict[str, float] = {"hinge": math.pi, "slide": 0.5}
#: Effort bound of a joint that declares none: N*m for hinges, N for slides
#: (set ``drive_pros.max_effort`` on the robot to use the real limits).
DEFAULT_QF_LIMIT: dict[str, float] = {"hinge": 5.0, "slide": 20.0}
#: Limits at or above this are "unlimited" (the entities report 1e10 for those).
_UNLIMITED = 1e9


def _joint_actuators(model: Any, jnt: int) -> list[int]:
    """Ids of the actuators whose transmission is MuJoCo joint ``jnt``."""
    return [
        a
        for a in range(model.nu)
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and model.actuator_trnid[a, 0] == jnt
    ]


def _velocity_actuator_limit(model: Any, act: int) -> float:
    """``max |ctrlrange|`` of a limited velocity servo (bias ``-kv * qdot``), else NaN."""
    bias = model.actuator_biasprm[act]
    servo = model.actuator_biastype[act] == mujoco.mjtBias.mjBIAS_AFFINE and bias[1] == 0 and bias[2] != 0
    if servo and model.actuator_ctrllimited[act]:
        return float(np.abs(model.actuator_ctrlrange[act]).max())
    return float("nan")


def _effort_actuator_limit(model: Any, act: int) -> float:
    """``max |forcerange|`` of a force-limited actuator, or ``ctrlrange * gain * gear`` of a
    limited motor, else NaN."""
    if model.actuator_forcelimited[act]:
        return float(np.abs(model.actuator_forcerange[act]).max())
    motor = (
        model.actuator_gaintype[act] == mujoco.mjtGain.mjGAIN_FIXED
        and model.actuator_biastype[act] == mujoco.mjtBias.mjBIAS_NONE
    )
    if motor and model.actuator_ctrllimited[act]:
        gain = abs(model.actuator_gainprm[act, 0] * model.actuator_gear[act, 0])
        return float(np.abs(model.actuator_ctrlrange[act]).max() * gain)
    return float("nan")


def _joint_bounds(term: _Term, configured: np.ndarray, from_actuator: Any, defaults: dict[str, float]) -> np.ndarray:
    """Per active joint: the configured limit when finite, else the largest limit an
    actuator on the joint gives (``from_actuator(model, act)``), else ``defaults[type]``."""
    model = term.robot.scene.model
    mj_joints = model.dof_jntid[term.robot.dof_adr.numpy()[term.joints.numpy()]]
    out = np.array(configured, dtype=np.float64)
    for k, jnt in enumerate(mj_joints.tolist()):
        if np.isfinite(out[k]) and 0 < out[k] < _UNLIMITED:
            continue
        found = [v for v in (from_actuator(model, a) for a in _joint_actuators(model, jnt)) if np.isfinite(v) and v > 0]
        hinge = model.jnt_type[jnt] == mujoco.mjtJoint.mjJNT_HINGE
        out[k] = max(found) if found else defaults["hinge" if hinge else "slide"]
    return out


class QvelTerm(_Term):
    """Joint velocity targets = ``scale * action``, driven by the joints' velocity drives.

    With ``zero_stiffness=True`` (default) the active joints' position gains are
    set to 0 when the term is built, so the drive torque is ``kv (qd* - qd)``
    (a PhysX velocity drive) instead of fighting the position target.

    The policy range is ``+-limit / scale`` per joint, ``limit`` being the first of: the
    robot's ``drive_pros.max_velocity``; the ``ctrlrange`` of a velocity actuator of the
    MJCF (kept with ``drive_type="none"``); :data:`DEFAULT_QVEL_LIMIT` by joint type.

    Params: ``scale`` (1.0), ``zero_stiffness`` (True).

    Example:
        ``{"func": "QvelTerm", "params": {"scale": 1.0}}``
    """

    input_key = "qvel"
    defaults = {"scale": 1.0, "zero_stiffness": True}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        if self.params["zero_stiffness"]:
            _disable_drive(self, stiffness=0.0)

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        configured = self.robot.get_qvel_limits()[0, self.joints].double().numpy()
        high = torch.as_tensor(_joint_bounds(self, configured, _velocity_actuator_limit, DEFAULT_QVEL_LIMIT))
        return -high / abs(self.scale), high / abs(self.scale)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return self.scale * torch.as_tensor(action, dtype=torch.float32)


class QfTerm(_Term):
    """Joint efforts = ``scale * action``, applied as joint forces (``qfrc_applied``).

    With ``disable_drives=True`` (default) the active joints' drive gains are set
    to 0 when the term is built, so the commanded effort is the only actuation.

    The policy range is ``+-limit / scale`` per joint, ``limit`` being the first of: the
    joint's effort limit (``drive_pros.max_effort`` or the MJCF ``actuatorfrcrange``); the
    ``forcerange`` of an actuator on the joint, or ``ctrlrange * gain * gear`` of a
    motor; :data:`DEFAULT_QF_LIMIT` by joint type.

    Params: ``scale`` (1.0), ``disable_drives`` (True).

    Example:
        ``{"func": "QfTerm", "params": {"scale": 5.0}}``
    """

    input_key = "qf"
    defaults = {"scale": 1.0, "disable_drives": True}

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        if self.params["disable_drives"]:
            _disable_drive(self, stiffness=0.0, damping=0.0)

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        configured = self.robot.get_qf_limits()[0, self.joints].double().numpy()
        high = torch.as_tensor(_joint_bounds(self, configured, _effort_actuator_limit, DEFAULT_QF_LIMIT))
        return -high / abs(self.scale), high / abs(self.scale)

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        return self.scale * torch.as_tensor(action, dtype=torch.float32)
