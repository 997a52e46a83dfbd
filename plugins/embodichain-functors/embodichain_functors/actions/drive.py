"""Velocity and effort action terms: they really drive velocity and effort."""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_functors.actions.base import _Term


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
