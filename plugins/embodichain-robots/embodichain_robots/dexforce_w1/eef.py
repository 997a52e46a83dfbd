"""W1 end effectors, authored in the ``{side}_ee`` frame (fingers along +z).

* BrainCo Revo1-like hand: 6 active joints (``{S}_HAND_THUMB1/THUMB2/INDEX/
  MIDDLE/RING/PINKY``) and 4 mimic ``{S}_{F}_PIP`` joints (joint equalities).
  Declaration order (index, middle, ring, pinky, thumb) gives EmbodiChain's
  breadth-first joint ids. Palm normal +y (left) / -y (right), thumb on +x.
* DH PGC-140-50-like parallel gripper: two prismatic fingers closing along y,
  0 = open, 0.025 = closed (``_M`` variant names ``{S}_FINGER1``; the plain
  variant ``{S}_FINGER1_JOINT`` with links ``*_link`` sits 15 mm further out).
"""

from __future__ import annotations

from typing import Optional, Sequence

import mujoco
import numpy as np

from embodichain_core.utils.math import matrix_to_quat
from embodichain_robots.dexforce_w1.params import DexforceW1HandBrand, drive_group
from embodichain_robots.spec_utils import add_body, add_geom, add_hinge, add_mimic, add_slide

#: Fingers in declaration order: name and x offset on the palm.
FINGERS = (("index", 0.027), ("middle", 0.009), ("ring", -0.009), ("pinky", -0.027))
PIP_MULTIPLIER = 1.0
FINGER_RANGE, PIP_RANGE = (0.0, 1.41), (0.0, 1.6)
THUMB_ROT_RANGE, THUMB_FLEX_RANGE = (0.0, 1.54), (0.0, 1.0)
GRIPPER_STROKE = 0.025


def build_eef(
    spec: mujoco.MjSpec, ee: mujoco.MjsBody, side: str, brand: DexforceW1HandBrand, mount: Optional[np.ndarray]
) -> None:
    """Mount ``brand`` on ``ee`` at the 4x4 ``mount`` (identity when None)."""
    mount = np.eye(4) if mount is None else np.asarray(mount, dtype=float)
    if brand == DexforceW1HandBrand.BRAINCO_HAND:
        build_brainco_hand(spec, ee, side, mount)
    else:
        build_gripper(ee, side, brand, mount)


def _mount_body(ee: mujoco.MjsBody, name: str, mount: np.ndarray, mass: float, ext: Sequence[float]) -> mujoco.MjsBody:
    return add_body(
        ee,
        name,
        mount[:3, 3].tolist(),
        matrix_to_quat(mount[:3, :3]).tolist(),
        mass=mass,
        inertia_box=ext,
        ipos=(0, 0, ext[2] / 2),
    )


def build_brainco_hand(spec: mujoco.MjSpec, ee: mujoco.MjsBody, side: str, mount: np.ndarray) -> None:
    """A dexterous hand: palm, four two-segment fingers and a two-joint thumb."""
    s, up = (1.0 if side == "left" else -1.0), side.upper()
    hand = _mount_body(ee, f"{side}_hand_base", mount, 0.5, (0.085, 0.03, 0.11))
    add_geom(hand, "cylinder", size=(0.032, 0.006), pos=(0, 0, 0.006), colour="black")
    add_geom(hand, "box", size=(0.0425, 0.015, 0.05), pos=(0, s * 0.01, 0.057), colour="grey", name=f"{side}_palm")
    add_geom(hand, "box", size=(0.04, 0.002, 0.045), pos=(0, s * -0.0055, 0.057), colour="black", visual=True)
    curl = (-1.0, 0.0, 0.0) if side == "left" else (1.0, 0.0, 0.0)
    for finger, x in FINGERS:
        prox = add_body(
            hand,
            f"{side}_{finger}_prox",
            (x, s * 0.01, 0.105),
            mass=0.02,
            inertia_box=(0.018, 0.018, 0.045),
            ipos=(0, 0, 0.022),
        )
        add_hinge(prox, f"{up}_HAND_{finger.upper()}", curl, FINGER_RANGE, *drive_group(f"{up}_HAND_INDEX"))
        add_geom(prox, "capsule", size=(0.009,), fromto=(0, 0, 0, 0, 0, 0.045), colour="grey")
        dist = add_body(
            prox,
            f"{side}_{finger}_dist",
            (0, 0, 0.045),
            mass=0.01,
            inertia_box=(0.016, 0.016, 0.035),
            ipos=(0, 0, 0.017),
        )
        add_hinge(dist, f"{up}_{finger.upper()}_PIP", curl, PIP_RANGE, *drive_group(f"{up}_HAND_INDEX"))
        add_geom(dist, "capsule", size=(0.008,), fromto=(0, 0, 0.002, 0, 0, 0.035), colour="black")
        dist.add_site(name=f"{side}_{finger}_tip", pos=[0, 0, 0.043], size=[0.004, 0, 0])
        add_mimic(spec, f"{up}_{finger.upper()}_PIP", f"{up}_HAND_{finger.upper()}", PIP_MULTIPLIER)
    _thumb(hand, side, s)


def _thumb(hand: mujoco.MjsBody, side: str, s: float) -> None:
    """THUMB2 rotates the thumb toward the palm side; THUMB1 flexes it."""
    up = side.upper()
    direction = np.array([0.6, 0.0, 0.8])
    prox = add_body(
        hand,
        f"{side}_thumb_prox",
        (0.03, s * 0.02, 0.035),
        mass=0.02,
        inertia_box=(0.02, 0.02, 0.04),
        ipos=(direction * 0.02).tolist(),
    )
    add_hinge(prox, f"{up}_HAND_THUMB2", (0, 0, s), THUMB_ROT_RANGE, *drive_group(f"{up}_HAND_THUMB2"))
    add_geom(prox, "capsule", size=(0.0105,), fromto=[0, 0, 0] + (direction * 0.04).tolist(), colour="grey")
    flex = np.cross(direction, [0.0, s, 0.0])
    dist = add_body(
        prox,
        f"{side}_thumb_dist",
        (direction * 0.04).tolist(),
        mass=0.01,
        inertia_box=(0.016, 0.016, 0.035),
        ipos=(direction * 0.017).tolist(),
    )
    add_hinge(dist, f"{up}_HAND_THUMB1", flex.tolist(), THUMB_FLEX_RANGE, *drive_group(f"{up}_HAND_THUMB1"))
    add_geom(dist, "capsule", size=(0.009,), fromto=[0, 0, 0] + (direction * 0.035).tolist(), colour="black")
    dist.add_site(name=f"{side}_thumb_tip", pos=(direction * 0.044).tolist(), size=[0.004, 0, 0])


def gripper_names(side: str, brand: DexforceW1HandBrand) -> tuple[list[str], list[str]]:
    """(joint names, finger link names) of a DH gripper variant."""
    up = side.upper()
    if brand == DexforceW1HandBrand.DH_PGC_GRIPPER_M:
        return [f"{up}_FINGER1", f"{up}_FINGER2"], [f"{side}_finger1", f"{side}_finger2"]
    return [f"{up}_FINGER1_JOINT", f"{up}_FINGER2_JOINT"], [f"{side}_finger1_link", f"{side}_finger2_link"]


def build_gripper(ee: mujoco.MjsBody, side: str, brand: DexforceW1HandBrand, mount: np.ndarray) -> None:
    """A two-finger parallel gripper; pads reach z ~= 0.15 (plain variant 0.165)."""
    mount = mount.copy()
    if brand == DexforceW1HandBrand.DH_PGC_GRIPPER:
        mount[:3, 3] += mount[:3, :3] @ np.array([0.0, 0.0, 0.015])
    base = _mount_body(ee, f"{side}_base_link_1", mount, 0.5, (0.075, 0.05, 0.10))
    add_geom(base, "box", size=(0.0375, 0.025, 0.05), pos=(0, 0, 0.05), colour="silver", name=f"{side}_gripper_body")
    add_geom(base, "box", size=(0.039, 0.027, 0.008), pos=(0, 0, 0.008), colour="black", visual=True)
    joints, links = gripper_names(side, brand)
    for k, (joint, link) in enumerate(zip(joints, links)):
        sy = 1.0 if k == 0 else -1.0
        finger = add_body(
            base, link, (0, sy * 0.03, 0.10), mass=0.05, inertia_box=(0.02, 0.012, 0.05), ipos=(0, 0, 0.025)
        )
        add_slide(finger, joint, (0, -sy, 0), (0.0, GRIPPER_STROKE), *drive_group(joint))
        add_geom(finger, "box", size=(0.01, 0.006, 0.025), pos=(0, 0, 0.025), colour="black")
