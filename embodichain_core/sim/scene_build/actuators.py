"""A loaded model's own actuators: replaced by the ``drive_pros`` drives, or kept.

By default (``keep_actuators: false``) the actuators a URDF/MJCF file declares are
removed and every non-mimic joint gets the core's two drive actuators from
``drive_pros``; one :class:`~embodichain_core.sim.scene_build.import_checks.ModelImportWarning`
names the removed actuators. With ``keep_actuators: true`` they stay:

* a kept *position servo* on a joint (``<position>``: fixed gain ``kp``, affine bias
  ``-kp q``) becomes that joint's position drive: ``set_qpos`` targets go to its ctrl and
  ``set_joint_drive`` changes its gains; a kept *velocity servo* (``<velocity>``)
  becomes its velocity drive;
* joints without a kept servo (passive, or driven by a ``<motor>``) get the
  ``drive_pros`` drives as usual;
* ``drive_pros``' joint properties (``armature``, ``friction``, ``max_effort``) apply to
  every driven joint on top.
"""

from __future__ import annotations

import warnings
from typing import Any

import mujoco
import numpy as np

from embodichain_core.sim.scene_build.import_checks import ModelImportWarning

_MAX_NAMED = 8


def actuator_label(act: Any, index: int) -> str:
    """An actuator's name, or ``#index`` for an unnamed one."""
    return act.name or f"#{index}"


def servo_kind(act: Any) -> str | None:
    """``"pos"`` / ``"vel"`` for a joint position / velocity servo, else None."""
    if act.trntype != mujoco.mjtTrn.mjTRN_JOINT or act.gaintype != mujoco.mjtGain.mjGAIN_FIXED:
        return None
    if act.biastype != mujoco.mjtBias.mjBIAS_AFFINE or act.dyntype != mujoco.mjtDyn.mjDYN_NONE:
        return None
    gain, bias = float(act.gainprm[0]), np.asarray(act.biasprm[:3], dtype=float)
    if gain > 0 and np.isclose(bias[1], -gain) and bias[0] == 0:
        return "pos"
    if gain > 0 and bias[1] == 0 and np.isclose(bias[2], -gain) and bias[0] == 0:
        return "vel"
    return None


def keep_servos(spec: mujoco.MjSpec, joints: list[str]) -> dict[str, dict[str, str]]:
    """Name the kept actuators and map ``joint -> {"pos"|"vel": actuator name}`` for servos
    on ``joints`` (the first servo of a kind per joint)."""
    out: dict[str, dict[str, str]] = {}
    for i, act in enumerate(spec.actuators):
        if not act.name:
            act.name = f"actuator{i}"
        kind = servo_kind(act)
        if kind is not None and act.target in joints:
            out.setdefault(act.target, {}).setdefault(kind, act.name)
    return out


def replace_actuators(spec: mujoco.MjSpec, owner: str) -> list[str]:
    """Delete the model's actuators; one notice names them. Returns their labels."""
    own = list(spec.actuators)
    labels = [actuator_label(a, i) for i, a in enumerate(own)]
    for act in own:
        spec.delete(act)
    if labels:
        shown = ", ".join(repr(n) for n in labels[:_MAX_NAMED]) + (", ..." if len(labels) > _MAX_NAMED else "")
        warnings.warn(
            f"{owner}: the model's {len(labels)} actuator(s) ({shown}) are replaced by drive_pros drives; "
            f"set keep_actuators: true to keep them",
            ModelImportWarning,
            stacklevel=4,
        )
    return labels


def drive_actuator_names(joints: list[str], servos: dict[str, dict[str, str]], added: list[str]) -> dict[str, tuple]:
    """``joint -> (position actuator name or None, velocity actuator name or None)``."""
    out: dict[str, tuple] = {}
    for joint in joints:
        kept = servos.get(joint, {})
        if joint in added:
            out[joint] = (f"{joint}:pos", f"{joint}:vel")
        elif kept:
            out[joint] = (kept.get("pos"), kept.get("vel"))
    return out
