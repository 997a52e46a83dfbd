"""The parametric description of the DexForce W1 (one source of truth).

Numbers follow the project's W1 reference (``w1_and_assets.md`` sections 2, 3
and 8): the arm block reproduces EmbodiChain's DH kinematics exactly; torso, head,
chassis, hand geometry and masses are estimates tuned against recorded scenes.
Frames: root x forward, y left, z up, origin on the floor under the chassis.
Lengths in metres, angles in radians unless a name ends in ``_DEG``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

SIDES = ("left", "right")
SQ = math.sqrt(0.5)


class DexforceW1Version(str, Enum):
    """Hardware versions; they differ (kinematically) only in the flange offset."""

    V021 = "v021"
    V022 = "v022"
    V025 = "v025"


class DexforceW1ArmKind(str, Enum):
    """Legacy arm kinds (EmbodiChain removed the key at HEAD; we still accept it)."""

    ANTHROPOMORPHIC = "anthropomorphic"
    INDUSTRIAL = "industrial"


class DexforceW1HandBrand(str, Enum):
    """End effectors that can be mounted on a W1 flange."""

    BRAINCO_HAND = "BRAINCO_HAND"
    DH_PGC_GRIPPER = "DH_PGC_GRIPPER"
    DH_PGC_GRIPPER_M = "DH_PGC_GRIPPER_M"


class DexforceW1HandVersion(str, Enum):
    """Hand versions (only v021 exists)."""

    V021 = "v021"


#: Flange offset along the ee z axis, per version (V025: +12 mm).
EEF_FLANGE_OFFSET = {DexforceW1Version.V021: 0.0, DexforceW1Version.V022: 0.0, DexforceW1Version.V025: 0.012}


@dataclass(frozen=True)
class JointSpec:
    """One body of the torso/head chain and the joint that moves it."""

    body: str
    parent: str
    pos: tuple
    joint: str
    axis: tuple = (0.0, 0.0, 1.0)
    limits: tuple = (0.0, 0.0)
    mass: float = 0.0


#: Torso and head chain (§8.2). Pitch joints turn about -y (positive ANKLE leans back).
TORSO_CHAIN = (
    JointSpec("ankle", "base_link", (0.0, 0.0, 0.25), "ANKLE", (0.0, -1.0, 0.0), (-0.52, 1.40), 4.0),
    JointSpec("knee", "ankle", (0.0, 0.0, 0.33), "KNEE", (0.0, -1.0, 0.0), (-2.62, 0.09), 4.0),
    JointSpec("buttock", "knee", (0.0, 0.0, 0.33), "BUTTOCK", (0.0, -1.0, 0.0), (-0.52, 1.75), 3.0),
    JointSpec("waist", "buttock", (0.0, 0.0, 0.07), "WAIST", (0.0, 0.0, 1.0), (-2.62, 2.62), 12.0),
)
HEAD_CHAIN = (
    JointSpec("neck1", "waist", (0.0, 0.0, 0.47), "NECK1", (0.0, 0.0, 1.0), (-1.57, 1.57), 0.5),
    JointSpec("neck2", "neck1", (0.0, 0.0, 0.07), "NECK2", (0.0, -1.0, 0.0), (-0.70, 0.70), 2.5),
)
CHASSIS_MASS = 50.0

#: ``eyes`` frame in ``neck2``: optical axis (-z) forward and 15 deg down at q = 0.
EYES_POS = (0.091, 0.0, 0.051)
EYES_QUAT = (0.56116, 0.43024, -0.43024, -0.56116)
#: Stereo pair in the eyes frame (OpenGL convention, baseline along +x).
STEREO_BASELINE = 0.06
EYES_RESOLUTION = (960, 540)
EYES_FOCAL_PX = 450.0

# --- arms (§2.4, §3.4, §8.2) ------------------------------------------------------------
ARM_MOUNT = (0.0, 0.0985, 0.3848)  # arm base in the waist frame (y mirrored for the right arm)
ARM_BASE_QUAT = {"left": (0.5, -0.5, -0.5, -0.5), "right": (0.5, 0.5, 0.5, -0.5)}
ARM_BASE_Z = 0.1025
UPPER_ARM = 0.26
FOREARM = 0.264
WRIST_TO_FLANGE = 0.066
ARM_LINK_MASSES = (1.2, 1.0, 1.5, 1.0, 1.0, 0.5, 0.4)

#: Joint limits in degrees per (side, kind); J6/J7 differ for the industrial arm.
_ANTHRO_LIMITS_DEG = {
    "left": ((-170, 170), (-120, 90), (-170, 170), (-135, 90), (-170, 170), (-45, 45), (-90, 60)),
    "right": ((-170, 170), (-90, 120), (-170, 170), (-90, 135), (-170, 170), (-45, 45), (-60, 90)),
}


def arm_limits(side: str, kind: DexforceW1ArmKind) -> tuple:
    """(7, 2) joint limits in radians of one arm."""
    deg = list(_ANTHRO_LIMITS_DEG[side])
    if kind == DexforceW1ArmKind.INDUSTRIAL:
        deg[5], deg[6] = (-90, 90), (-170, 170)
    return tuple((math.radians(lo), math.radians(hi)) for lo, hi in deg)


def arm_axes(side: str, kind: DexforceW1ArmKind) -> tuple:
    """Joint axes J1..J7 in their body frames (arm-base orientation)."""
    elbow = (1.0, 0.0, 0.0) if side == "left" else (-1.0, 0.0, 0.0)
    j7 = (0.0, 0.0, 1.0) if kind == DexforceW1ArmKind.INDUSTRIAL else (0.0, 1.0, 0.0)
    return ((0, 0, 1.0), (0, 1.0, 0), (0, 0, 1.0), elbow, (0, 0, 1.0), elbow, j7)


def ee_quat(kind: DexforceW1ArmKind) -> tuple:
    """``{side}_ee`` in ``{side}_link7``: Rz(+90) (industrial: Rz(-90))."""
    return (SQ, 0.0, 0.0, -SQ) if kind == DexforceW1ArmKind.INDUSTRIAL else (SQ, 0.0, 0.0, SQ)


#: Wrist camera bodies in ``{side}_ee``.
WRIST_CAMERA = {
    "left": ((0.0, -0.08, 0.06), (0.17364, 0.98481, 0.0, 0.0)),
    "right": ((0.0, 0.08, 0.06), (0.0, 0.0, 0.98481, 0.17364)),
}
WRIST_CAMERA_RESOLUTION = (640, 360)
WRIST_CAMERA_FOCAL_PX = (337.0, 325.0)

#: Default TCPs in the ee frame, as 4x4 row lists (before the version flange offset).
TCP_BRAINCO = {
    "left": ((-1, 0, 0, 0.012), (0, 0, 1, 0.0675), (0, 1, 0, 0.127), (0, 0, 0, 1)),
    "right": ((1, 0, 0, 0.012), (0, 0, -1, -0.0675), (0, 1, 0, 0.127), (0, 0, 0, 1)),
}
TCP_GRIPPER = ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0.15), (0, 0, 0, 1))

# --- EmbodiChain DH description of one arm (the solver's reference FK) ------------------
#: rows (d, alpha, a, theta0); row 6 theta0 is 0 for the industrial arm.
DH_ROWS = (
    (0.0, -math.pi / 2, 0.0, 0.0),
    (0.0, math.pi / 2, 0.0, 0.0),
    (UPPER_ARM, math.pi / 2, 0.0, math.pi / 2),
    (0.0, -math.pi / 2, 0.0, 0.0),
    (FOREARM, -math.pi / 2, 0.0, 0.0),
    (0.0, math.pi / 2, 0.0, math.pi / 2),
    (0.0, 0.0, 0.0, 0.0),
)
ROTATION_DIRECTIONS = {"left": (1, 1, 1, 1, 1, -1, 1), "right": (1, 1, 1, -1, 1, 1, 1)}
T_E_OE = {
    DexforceW1ArmKind.ANTHROPOMORPHIC: ((0, 0, -1, -WRIST_TO_FLANGE), (0, 1, 0, 0), (1, 0, 0, 0), (0, 0, 0, 1)),
    DexforceW1ArmKind.INDUSTRIAL: ((-1, 0, 0, 0), (0, -1, 0, 0), (0, 0, 1, WRIST_TO_FLANGE), (0, 0, 0, 1)),
}

# --- drives (§2.2 regexes, §8.6 MuJoCo-stable values) -----------------------------------
ARM_RE = "(RIGHT|LEFT)_J[0-9]"
TORSO_RE = "(ANKLE|KNEE|BUTTOCK|WAIST)"
HEAD_RE = "(NECK1|NECK2)"
HAND_RE = "(LEFT|RIGHT)_(HAND_(THUMB[12]|INDEX|MIDDLE|RING|PINKY)|FINGER[12](_JOINT)?)"
#: group -> (regex, stiffness, damping, max_effort, armature, joint damping).
DRIVE_GROUPS = {
    "arm": (ARM_RE, 1e4, 1e3, 300.0, 0.05, 0.5),
    "torso": (TORSO_RE, 1e6, 1e4, 5000.0, 0.5, 5.0),
    "head": (HEAD_RE, 1e4, 1e3, 100.0, 0.02, 0.2),
    "hand": (HAND_RE, 1e2, 1e1, 20.0, 0.005, 0.05),
}
#: EmbodiChain's own values (PhysX): kept for reference in the docs.
EMBODICHAIN_DRIVES = {
    "arm": (1e4, 1e3, 1e5),
    "torso": (1e7, 1e4, 1e10),
    "head": (1e4, 1e3, 1e5),
    "hand": (1e2, 1e1, 1e3),
}


def drive_group(joint: str) -> tuple:
    """(armature, joint damping) of a joint name, from :data:`DRIVE_GROUPS`."""
    import re

    for regex, *_, armature, damping in DRIVE_GROUPS.values():
        if re.fullmatch(regex, joint):
            return armature, damping
    return 0.0, 0.0
