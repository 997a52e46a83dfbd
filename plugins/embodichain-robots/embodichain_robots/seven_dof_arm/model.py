"""A Franka-Panda-like 7-DoF arm with a parallel gripper, generated with MjSpec.

Kinematics follow the Panda's published (modified) DH parameters and joint
limits; geometry is primitives (white shells, dark joints). Bodies ``link0``
(root) .. ``link7``, ``hand``, ``left_finger``, ``right_finger``; joints
``joint1..7`` and ``finger_joint1/2`` (the second finger mimics the first;
0 = closed, 0.04 = open); sites ``tcp`` (between the finger pads) and ``ee``.
"""

from __future__ import annotations

import math

import mujoco

from embodichain_robots.spec_utils import add_body, add_geom, add_hinge, add_mimic, add_slide, new_spec

SQ = math.sqrt(0.5)
RX_POS, RX_NEG = (SQ, SQ, 0.0, 0.0), (SQ, -SQ, 0.0, 0.0)
#: (body pos in parent, body quat, joint limits) of link1..7 (Panda DH).
LINKS = (
    ((0, 0, 0.333), (1, 0, 0, 0), (-2.8973, 2.8973)),
    ((0, 0, 0), RX_NEG, (-1.7628, 1.7628)),
    ((0, -0.316, 0), RX_POS, (-2.8973, 2.8973)),
    ((0.0825, 0, 0), RX_POS, (-3.0718, -0.0698)),
    ((-0.0825, 0.384, 0), RX_NEG, (-2.8973, 2.8973)),
    ((0, 0, 0), RX_POS, (-0.0175, 3.7525)),
    ((0.088, 0, 0), RX_POS, (-2.8973, 2.8973)),
)
LINK_MASSES = (4.97, 0.65, 3.23, 3.59, 1.23, 1.67, 0.74)
FLANGE = 0.107
TCP_OFFSET = 0.1034
FINGER_RANGE = (0.0, 0.04)
HOME_QPOS = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785, 0.04, 0.04)
ARMATURE, JOINT_DAMPING = 0.1, 1.0


def build_arm_spec(name: str = "seven_dof_arm") -> mujoco.MjSpec:
    """The arm as an ``MjSpec`` (no actuators: the core adds the drives)."""
    spec = new_spec(name)
    parent = add_body(spec.worldbody, "link0", mass=3.0, inertia_box=(0.2, 0.2, 0.15), ipos=(0, 0, 0.07))
    _base_shell(parent)
    for i, (pos, quat, limits) in enumerate(LINKS):
        link = add_body(parent, f"link{i + 1}", pos, quat, mass=LINK_MASSES[i], inertia_box=(0.12, 0.12, 0.2))
        add_hinge(link, f"joint{i + 1}", (0, 0, 1), limits, ARMATURE, JOINT_DAMPING)
        _LINK_SHELLS[i](link)
        parent = link
    _hand(spec, parent)
    return spec


def _base_shell(link0: mujoco.MjsBody) -> None:
    add_geom(link0, "box", size=(0.11, 0.09, 0.015), pos=(-0.03, 0, 0.015), colour="grey", name="base_plate")
    add_geom(link0, "cylinder", size=(0.065,), fromto=(0, 0, 0.0, 0, 0, 0.14), colour="white")


def _joint_ring(link: mujoco.MjsBody, radius: float = 0.062, half: float = 0.055) -> None:
    add_geom(link, "cylinder", size=(radius, half), colour="black", visual=True)


def _link1(b: mujoco.MjsBody) -> None:
    add_geom(b, "capsule", size=(0.062,), fromto=(0, 0, -0.19, 0, 0, -0.02), colour="white")


def _link2(b: mujoco.MjsBody) -> None:
    _joint_ring(b)
    add_geom(b, "capsule", size=(0.06,), fromto=(0, 0, 0, 0, -0.13, 0), colour="white")


def _link3(b: mujoco.MjsBody) -> None:
    add_geom(b, "capsule", size=(0.058,), fromto=(0, 0, -0.17, 0, 0, -0.03), colour="white")
    add_geom(b, "capsule", size=(0.055,), fromto=(0, 0, 0, 0.0825, 0, 0), colour="white", visual=True)


def _link4(b: mujoco.MjsBody) -> None:
    _joint_ring(b, 0.06, 0.05)
    add_geom(b, "capsule", size=(0.055,), fromto=(0, 0, 0, -0.0825, 0.1, 0), colour="white")


def _link5(b: mujoco.MjsBody) -> None:
    add_geom(b, "capsule", size=(0.05,), fromto=(0, 0, -0.27, 0, 0, -0.08), colour="white")
    add_geom(b, "box", size=(0.03, 0.02, 0.06), pos=(0, 0.04, -0.1), colour="white", visual=True)


def _link6(b: mujoco.MjsBody) -> None:
    _joint_ring(b, 0.055, 0.05)
    add_geom(b, "capsule", size=(0.045,), fromto=(0, 0, 0, 0.088, 0, 0), colour="white")


def _link7(b: mujoco.MjsBody) -> None:
    add_geom(b, "cylinder", size=(0.05,), fromto=(0, 0, -0.05, 0, 0, FLANGE - 0.01), colour="black")
    add_geom(b, "cylinder", size=(0.05, 0.006), pos=(0, 0, FLANGE - 0.006), colour="grey", visual=True)


_LINK_SHELLS = (_link1, _link2, _link3, _link4, _link5, _link6, _link7)


def _hand(spec: mujoco.MjSpec, link7: mujoco.MjsBody) -> None:
    """Hand rotated -45 deg about z (as on the Panda), fingers closing along its y."""
    hand = add_body(
        link7,
        "hand",
        (0, 0, FLANGE),
        (math.cos(-math.pi / 8), 0, 0, math.sin(-math.pi / 8)),
        mass=0.73,
        inertia_box=(0.05, 0.2, 0.07),
        ipos=(0, 0, 0.03),
    )
    hand.add_site(name="ee", size=[0.006, 0, 0])
    hand.add_site(name="tcp", pos=[0, 0, TCP_OFFSET], size=[0.008, 0, 0], rgba=[0.1, 0.8, 0.2, 0.6], group=4)
    add_geom(hand, "box", size=(0.025, 0.095, 0.025), pos=(0, 0, 0.03), colour="white", name="hand")
    add_geom(hand, "cylinder", size=(0.04, 0.01), pos=(0, 0, 0.005), colour="black", visual=True)
    for name, joint, sign in (("left_finger", "finger_joint1", 1.0), ("right_finger", "finger_joint2", -1.0)):
        finger = add_body(hand, name, (0, 0, 0.0584), mass=0.015, inertia_box=(0.02, 0.02, 0.05), ipos=(0, 0, 0.025))
        add_slide(finger, joint, (0, sign, 0), FINGER_RANGE, armature=0.01, damping=0.1)
        add_geom(finger, "box", size=(0.01, 0.01, 0.026), pos=(0, sign * 0.01, 0.026), colour="grey")
        add_geom(
            finger, "box", size=(0.0085, 0.003, 0.012), pos=(0, sign * 0.003, 0.039), colour="black", name=f"{name}_pad"
        )
    add_mimic(spec, "finger_joint2", "finger_joint1")
