"""W1 chassis, torso column and head (with the ``eyes`` stereo frame)."""

from __future__ import annotations

import math

import mujoco

from embodichain_robots.dexforce_w1 import params as P
from embodichain_robots.spec_utils import add_body, add_geom, add_hinge, axis_quat


def build_chassis(world: mujoco.MjsBody) -> mujoco.MjsBody:
    """``base_link``: a rounded square wheeled base about 0.6 m wide (0 DOF)."""
    base = add_body(world, "base_link", mass=P.CHASSIS_MASS, inertia_box=(0.6, 0.56, 0.2), ipos=(0, 0, 0.12))
    add_geom(base, "box", size=(0.28, 0.26, 0.075), pos=(0, 0, 0.135), colour="yellow", name="chassis")
    for sx in (-1, 1):  # rounded front/back edges
        add_geom(
            base,
            "cylinder",
            size=(0.075, 0.26),
            pos=(sx * 0.28, 0, 0.135),
            quat=axis_quat("y"),
            colour="yellow",
            visual=True,
        )
    add_geom(base, "box", size=(0.30, 0.28, 0.03), pos=(0, 0, 0.055), colour="black", name="bumper")
    add_geom(base, "box", size=(0.20, 0.16, 0.004), pos=(0, 0, 0.212), colour="black", visual=True)
    for sx in (-1, 1):
        for sy in (-1, 1):
            add_geom(
                base,
                "cylinder",
                size=(0.05, 0.02),
                pos=(sx * 0.2, sy * 0.295, 0.05),
                quat=axis_quat("y"),
                colour="black",
                name=f"wheel_{'fb'[sx > 0]}{'rl'[sy > 0]}",
            )
            add_geom(
                base,
                "cylinder",
                size=(0.025, 0.021),
                pos=(sx * 0.2, sy * 0.295, 0.05),
                quat=axis_quat("y"),
                colour="silver",
                visual=True,
            )
    add_geom(base, "box", size=(0.08, 0.08, 0.025), pos=(0, 0, 0.225), colour="black", name="ankle_mount")
    return base


def _hub(body: mujoco.MjsBody, radius: float, half: float) -> None:
    """A dark pitch-joint housing along y at the body origin."""
    add_geom(body, "cylinder", size=(radius, half), quat=axis_quat("y"), colour="black")


def build_torso(base: mujoco.MjsBody) -> mujoco.MjsBody:
    """ANKLE, KNEE, BUTTOCK (pitch about -y) and WAIST (yaw); returns ``waist``."""
    bodies = {"base_link": base}
    shapes = {"ankle": (0.06, 0.33), "knee": (0.065, 0.33)}
    for js in P.TORSO_CHAIN:
        ext = (0.16, 0.16, 0.33) if js.body in shapes else (0.22, 0.34, 0.42)
        ipos = (0, 0, 0.165) if js.body in shapes else (0, 0, 0.035 if js.body == "buttock" else 0.21)
        body = add_body(bodies[js.parent], js.body, js.pos, mass=js.mass, inertia_box=ext, ipos=ipos)
        armature, damping = P.drive_group(js.joint)
        add_hinge(body, js.joint, js.axis, js.limits, armature, damping)
        if js.body in shapes:
            r, seg = shapes[js.body]
            _hub(body, r + 0.012, 0.075)
            add_geom(body, "capsule", size=(r,), fromto=(0, 0, 0.04, 0, 0, seg - 0.04), colour="yellow")
        bodies[js.body] = body
    _hub(bodies["buttock"], 0.072, 0.08)
    add_geom(bodies["buttock"], "box", size=(0.08, 0.11, 0.035), pos=(0, 0, 0.035), colour="black", name="pelvis")
    _torso_shell(bodies["waist"])
    return bodies["waist"]


def _torso_shell(waist: mujoco.MjsBody) -> None:
    """Chest box with a dark front panel and shoulder caps."""
    add_geom(waist, "cylinder", size=(0.09, 0.02), pos=(0, 0, 0.02), colour="black")
    add_geom(waist, "box", size=(0.11, 0.17, 0.19), pos=(0, 0, 0.23), colour="yellow", name="chest")
    add_geom(waist, "box", size=(0.105, 0.16, 0.025), pos=(0, 0, 0.025 + 0.02), colour="yellow", visual=True)
    add_geom(waist, "box", size=(0.004, 0.11, 0.11), pos=(0.111, 0, 0.23), colour="black", visual=True)
    add_geom(waist, "box", size=(0.004, 0.05, 0.012), pos=(0.116, 0, 0.30), colour="orange", visual=True)
    for sy in (-1, 1):
        add_geom(waist, "sphere", size=(0.055,), pos=(0, sy * 0.15, 0.385), colour="black")
    add_geom(waist, "box", size=(0.09, 0.12, 0.02), pos=(0, 0, 0.43), colour="black", visual=True)


def build_head(waist: mujoco.MjsBody) -> mujoco.MjsBody:
    """NECK1 (yaw) and NECK2 (pitch about -y), a head shell and the ``eyes`` frame."""
    neck_spec, head_spec = P.HEAD_CHAIN
    neck1 = add_body(
        waist, neck_spec.body, neck_spec.pos, mass=neck_spec.mass, inertia_box=(0.07, 0.07, 0.07), ipos=(0, 0, 0.035)
    )
    add_hinge(neck1, neck_spec.joint, neck_spec.axis, neck_spec.limits, *P.drive_group(neck_spec.joint))
    add_geom(neck1, "cylinder", size=(0.035,), fromto=(0, 0, -0.04, 0, 0, 0.07), colour="black")
    neck2 = add_body(
        neck1, head_spec.body, head_spec.pos, mass=head_spec.mass, inertia_box=(0.18, 0.18, 0.22), ipos=(0, 0, 0.07)
    )
    add_hinge(neck2, head_spec.joint, head_spec.axis, head_spec.limits, *P.drive_group(head_spec.joint))
    _head_shell(neck2)
    build_eyes(neck2)
    return neck2


def _head_shell(neck2: mujoco.MjsBody) -> None:
    """Head ellipsoid kept behind the eyes (x < 0.09) so the eye cameras see out."""
    add_geom(neck2, "ellipsoid", size=(0.09, 0.095, 0.105), pos=(-0.006, 0, 0.075), colour="yellow", name="head")
    add_geom(neck2, "box", size=(0.006, 0.07, 0.028), pos=(0.078, 0, 0.052), colour="glass", visual=True)
    for sy in (-1, 1):
        add_geom(
            neck2,
            "cylinder",
            size=(0.03, 0.008),
            pos=(-0.006, sy * 0.095, 0.075),
            quat=axis_quat("y"),
            colour="black",
            visual=True,
        )


def build_eyes(neck2: mujoco.MjsBody) -> mujoco.MjsBody:
    """``eyes``: stereo cameras ``eyes_left``/``eyes_right`` and a site ``eyes``.

    MuJoCo cameras look along -z with +y up, EmbodiChain's (OpenGL) convention,
    so a camera with identity extrinsics in ``eyes`` is the eye camera.
    """
    eyes = add_body(neck2, "eyes", P.EYES_POS, P.EYES_QUAT)
    eyes.add_site(name="eyes", size=[0.005, 0, 0])
    width, height = P.EYES_RESOLUTION
    fovy = math.degrees(2 * math.atan(height / 2 / P.EYES_FOCAL_PX))
    for name, x in (("eyes_left", -P.STEREO_BASELINE / 2), ("eyes_right", P.STEREO_BASELINE / 2)):
        eyes.add_camera(name=name, pos=[x, 0, 0], fovy=fovy, resolution=[width, height])
    return eyes
