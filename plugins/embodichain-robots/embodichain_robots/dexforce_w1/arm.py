"""W1 7-DoF S-R-S arms: ``{side}_arm_base`` -> ``{side}_link1..7`` -> ``{side}_ee``.

The link frames keep the arm-base orientation (x up/down, y forward, z along the
arm), which makes MuJoCo's FK equal EmbodiChain's DH FK with its rotation
directions (see :func:`embodichain_robots.kinematics.dh.w1_arm_dh_fk`).
"""

from __future__ import annotations

import math

import mujoco

from embodichain_robots.dexforce_w1 import params as P
from embodichain_robots.spec_utils import add_body, add_geom, add_hinge, axis_quat

#: (body offset along the arm from the previous link, shell geoms) per link 1..7.
_OFFSETS = (P.ARM_BASE_Z, 0.0, 0.0, P.UPPER_ARM, 0.0, P.FOREARM, 0.0)


def build_arm(waist: mujoco.MjsBody, side: str, kind: P.DexforceW1ArmKind) -> mujoco.MjsBody:
    """Add one arm under ``waist``; return its ``{side}_ee`` body."""
    sign = 1.0 if side == "left" else -1.0
    mount = (P.ARM_MOUNT[0], sign * P.ARM_MOUNT[1], P.ARM_MOUNT[2])
    base = add_body(waist, f"{side}_arm_base", mount, P.ARM_BASE_QUAT[side], mass=0.5, inertia_box=(0.1, 0.1, 0.1))
    add_geom(base, "cylinder", size=(0.05,), fromto=(0, 0, 0.0, 0, 0, 0.055), colour="black")
    parent = base
    axes, limits = P.arm_axes(side, kind), P.arm_limits(side, kind)
    upper = side.upper()
    for i in range(7):
        length = {2: P.UPPER_ARM, 4: P.FOREARM, 6: P.WRIST_TO_FLANGE}.get(i, 0.1)
        link = add_body(
            parent,
            f"{side}_link{i + 1}",
            (0, 0, _OFFSETS[i]),
            mass=P.ARM_LINK_MASSES[i],
            inertia_box=(0.08, 0.08, length),
            ipos=(0, 0, length / 2 if i in (2, 4, 6) else 0.0),
        )
        joint = f"{upper}_J{i + 1}"
        add_hinge(link, joint, axes[i], limits[i], *P.drive_group(joint))
        _link_shell(link, i)
        parent = link
    ee = add_body(parent, f"{side}_ee", (0, 0, P.WRIST_TO_FLANGE), P.ee_quat(kind))
    ee.add_site(name=f"{side}_ee", size=[0.006, 0, 0], rgba=[0.9, 0.2, 0.2, 1])
    _wrist_camera(ee, side)
    return ee


def _link_shell(link: mujoco.MjsBody, index: int) -> None:
    """Yellow shells on the long links, dark housings on the joints."""
    if index == 0:
        add_geom(link, "sphere", size=(0.05,), colour="black")
    elif index == 1:
        add_geom(link, "cylinder", size=(0.052, 0.045), quat=axis_quat("y"), colour="yellow", visual=True)
    elif index == 2:
        add_geom(link, "capsule", size=(0.045,), fromto=(0, 0, 0.05, 0, 0, 0.215), colour="yellow")
    elif index == 3:
        add_geom(link, "sphere", size=(0.047,), colour="black")
        add_geom(link, "cylinder", size=(0.05, 0.04), quat=axis_quat("x"), colour="black", visual=True)
    elif index == 4:
        add_geom(link, "capsule", size=(0.04,), fromto=(0, 0, 0.045, 0, 0, 0.225), colour="yellow")
    elif index == 5:
        add_geom(link, "sphere", size=(0.037,), colour="black")
    else:
        add_geom(link, "cylinder", size=(0.035,), fromto=(0, 0, 0.0, 0, 0, 0.062), colour="black")


def _wrist_camera(ee: mujoco.MjsBody, side: str) -> None:
    """``{side}_wrist_camera`` body with a camera of the same name and a housing."""
    pos, quat = P.WRIST_CAMERA[side]
    body = add_body(ee, f"{side}_wrist_camera", pos, quat)
    width, height = P.WRIST_CAMERA_RESOLUTION
    fovy = math.degrees(2 * math.atan(height / 2 / P.WRIST_CAMERA_FOCAL_PX[1]))
    body.add_camera(name=f"{side}_wrist_camera", fovy=fovy, resolution=[width, height])
    # housing behind the lens (the camera looks along its -z) on a bracket over the wrist
    add_geom(body, "box", size=(0.02, 0.013, 0.014), pos=(0, 0, 0.015), colour="black", visual=True)
    add_geom(body, "cylinder", size=(0.007, 0.002), pos=(0, 0, 0.0), colour="glass", visual=True)
    add_geom(
        ee,
        "box",
        size=(0.012, 0.022, 0.012),
        pos=(0, -0.05 if side == "left" else 0.05, 0.035),
        colour="black",
        visual=True,
    )
