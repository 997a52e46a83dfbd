"""Articulations and robots on the scene spec: attach, drives, joint order.

Joint drives are two MuJoCo actuators per driven joint, ``<joint>:pos`` (gain kp,
bias -kp*q) and ``<joint>:vel`` (gain kv, bias -kv*qdot), so a position target
and a velocity target act together like a PhysX drive:
``tau = kp (q* - q) + kv (qd* - qd)``, clamped to ``max_effort`` on the joint.
Feed-forward efforts go through ``qfrc_applied``.
"""

from __future__ import annotations

import re
from collections import deque
from typing import Any

import mujoco
import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.scene_build.actuators import drive_actuator_names, keep_servos, replace_actuators
from embodichain_core.sim.scene_build.builder import EntityRecord, SceneBuilder
from embodichain_core.sim.scene_build.drive_values import joint_value
from embodichain_core.sim.scene_build.import_checks import balance_inertias
from embodichain_core.sim.cfg import ArticulationCfg, JointDrivePropertiesCfg
from embodichain_core.utils.math import init_pos_from_cfg, init_quat_from_cfg

ALL_COLLISION_BITS = (1 << 30) - 1  # bit 30: parked geoms (see variants.py)
_MOVABLE = (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)


def add_articulation(builder: SceneBuilder, cfg: ArticulationCfg, kind: str, path: str) -> EntityRecord:
    """Attach an articulation (``kind`` ``robot`` or ``articulation``) to the scene."""
    record = builder.claim_uid(cfg.uid, kind, cfg, path)
    builder.require_iterations(cfg, cfg.attrs)
    child = _load_spec(cfg, path)
    root = child.worldbody.first_body()
    if root is None:
        raise ConfigError(path, f"{kind} {cfg.uid!r}: the model has no body")
    joints = bfs_joints(root)
    mimic = _mimic_joints(child)
    driven = [j for j in joints if j not in mimic]
    owner = f"{path}: {kind} {cfg.uid!r}"
    balance_inertias(child, owner)
    keep = bool(getattr(cfg, "keep_actuators", False))
    servos = keep_servos(child, driven) if keep else {}
    added: list[str] = []
    if cfg.drive_pros.drive_type != "none":
        if not keep:
            replace_actuators(child, owner)
        added = [j for j in driven if j not in servos]
        _add_drives(child, driven, cfg.drive_pros, f"{path}.drive_pros", skip_actuators=set(servos))
    drives = drive_actuator_names(driven, servos, added)
    _apply_qpos_limits(child, joints, cfg.qpos_limits, f"{path}.qpos_limits")
    if not cfg.fix_base and not any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in root.joints):
        root.add_freejoint(name="root_free")
    builder.collision_bit += 1
    _configure_bodies(child, cfg, is_robot=kind == "robot", bit=builder.collision_bit)
    frame = builder.spec.worldbody.add_frame(
        pos=init_pos_from_cfg(cfg.init_pos, cfg.init_local_pose),
        quat=init_quat_from_cfg(cfg.init_rot, cfg.init_local_pose),
    )
    root_name = root.name or "base"
    root.name = root_name
    builder.sleep_policy(root, cfg.sleep_threshold)
    bodies = bfs_bodies(root)
    builder.spec.attach(child, frame=frame, prefix=f"{cfg.uid}/")
    record.root_body = f"{cfg.uid}/{root_name}"
    record.extra.update(
        joints=joints,
        mimic=mimic,
        driven=[j for j in driven if j in drives],
        drive_actuators=drives,
        bodies=bodies,
    )
    return record


def _load_spec(cfg: ArticulationCfg, path: str) -> mujoco.MjSpec:
    try:
        return cfg.build_spec()
    except ConfigError as err:
        raise err.under(path)
    except FileNotFoundError as err:
        raise ConfigError(f"{path}.fpath", str(err)) from err
    except Exception as err:
        raise ConfigError(path, f"cannot load the model of {cfg.uid!r}: {err}") from err


def bfs_bodies(root: Any) -> list[str]:
    """Body names in breadth-first order, children in declaration order."""
    out, queue = [], deque([root])
    while queue:
        body = queue.popleft()
        out.append(body.name)
        queue.extend(_children(body))
    return out


def bfs_joints(root: Any) -> list[str]:
    """Hinge/slide joint names in EmbodiChain's breadth-first link order."""
    out, queue = [], deque([root])
    while queue:
        body = queue.popleft()
        out += [j.name for j in body.joints if j.type in _MOVABLE]
        queue.extend(_children(body))
    missing = [i for i, name in enumerate(out) if not name]
    if missing:
        raise ValueError("every hinge/slide joint of an articulation needs a name")
    return out


def _children(body: Any) -> list[Any]:
    out, child = [], body.first_body()
    while child is not None:
        out.append(child)
        child = body.next_body(child)
    return out


def _mimic_joints(spec: mujoco.MjSpec) -> dict[str, tuple[str, float, float]]:
    """Joints that follow another through a joint equality: name -> (parent, k, offset)."""
    out = {}
    for eq in spec.equalities:
        if eq.type == mujoco.mjtEq.mjEQ_JOINT and eq.name2:
            coef = np.asarray(eq.data, dtype=float)
            out[eq.name1] = (eq.name2, float(coef[1]), float(coef[0]))
    return out


def _add_drives(
    spec: mujoco.MjSpec,
    joints: list[str],
    drive: JointDrivePropertiesCfg,
    path: str,
    skip_actuators: frozenset[str] | set[str] = frozenset(),
) -> None:
    """Joint properties of ``drive`` on ``joints``, and their two drive actuators (except for
    the joints in ``skip_actuators``: they keep the model's own servos)."""
    defaults = JointDrivePropertiesCfg()
    for name in joints:
        joint = spec.joint(name)
        vals = {}
        for key in ("stiffness", "damping", "max_effort", "friction", "armature"):
            v = joint_value(getattr(drive, key), name, f"{path}.{key}")
            vals[key] = (
                v if np.isfinite(v) else float(getattr(defaults, key)) if key in ("stiffness", "damping") else np.nan
            )
        if np.isfinite(vals["armature"]) and vals["armature"] > 0:
            joint.armature = vals["armature"]
        if np.isfinite(vals["friction"]) and vals["friction"] > 0:
            joint.frictionloss = vals["friction"]
        if np.isfinite(vals["max_effort"]) and vals["max_effort"] < 1e9:
            joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
            joint.actfrcrange = [-vals["max_effort"], vals["max_effort"]]
        if name in skip_actuators:
            continue
        _drive_actuator(spec, name, "pos", gain=vals["stiffness"], bias=[0.0, -vals["stiffness"], 0.0])
        _drive_actuator(spec, name, "vel", gain=vals["damping"], bias=[0.0, 0.0, -vals["damping"]])


def _drive_actuator(spec: mujoco.MjSpec, joint: str, kind: str, gain: float, bias: list[float]) -> None:
    act = spec.add_actuator(name=f"{joint}:{kind}", target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    gainprm = np.zeros(10)
    gainprm[0] = gain
    biasprm = np.zeros(10)
    biasprm[:3] = bias
    act.gainprm, act.biasprm = gainprm, biasprm
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE


def _apply_qpos_limits(spec: mujoco.MjSpec, joints: list[str], limits: Any, path: str) -> None:
    if limits is None:
        return
    if isinstance(limits, dict):
        for pattern, rng in limits.items():
            hits = [j for j in joints if re.fullmatch(pattern, j)]
            if not hits:
                raise ConfigError(f"{path}.{pattern}", f"matches no joint; joints are {joints}")
            for j in hits:
                _set_range(spec.joint(j), rng, f"{path}.{pattern}")
        return
    arr = np.asarray(limits, dtype=float)
    if arr.shape != (len(joints), 2):
        raise ConfigError(path, f"expected shape ({len(joints)}, 2) (one [min, max] per joint), got {arr.shape}")
    for j, rng in zip(joints, arr):
        _set_range(spec.joint(j), rng, path)


def _set_range(joint: Any, rng: Any, path: str) -> None:
    lo, hi = (float(v) for v in rng)
    if lo > hi:
        raise ConfigError(path, f"lower limit {lo} is above upper limit {hi} for joint {joint.name!r}")
    joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    joint.range = [lo, hi]


def _configure_bodies(spec: mujoco.MjSpec, cfg: ArticulationCfg, is_robot: bool, bit: int) -> None:
    """Gravity compensation for robots; with ``disable_self_collision`` each
    articulation gets its own contype bit that its own geoms do not accept."""
    gravcomp = is_robot and bool(getattr(cfg, "gravity_compensation", False))
    for body in spec.bodies:
        if body.name == "world":
            continue
        if gravcomp:
            body.gravcomp = 1.0
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:
            continue
        geom.friction = [float(cfg.attrs.static_friction), geom.friction[1], geom.friction[2]]
        if cfg.disable_self_collision:
            own = 1 << min(bit, 29)
            geom.contype, geom.conaffinity = own, ALL_COLLISION_BITS ^ own
