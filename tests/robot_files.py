"""Robot description files written by the tests: a 6-DoF URDF arm with STL meshes and an
MJCF arm with its own actuators (a uniquely named module: plugin tests import it too).

The URDF arm is a UR-like 6R chain (``base_link`` -> ``flange``, ``shoulder_pan`` continuous)
with a two-finger gripper whose right finger mimics the left one. Meshes are binary STL
boxes, referenced as ``package://test_arm/meshes/...`` and as relative paths.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

#: (joint, parent link, child link, origin xyz, axis) of the 6R chain.
ARM_JOINTS = [
    ("shoulder_pan", "base_link", "shoulder", (0, 0, 0.1), (0, 0, 1)),
    ("shoulder_lift", "shoulder", "upper_arm", (0, 0.07, 0.06), (0, 1, 0)),
    ("elbow", "upper_arm", "forearm", (0, -0.05, 0.3), (0, 1, 0)),
    ("wrist_1", "forearm", "wrist1", (0, 0, 0.27), (0, 1, 0)),
    ("wrist_2", "wrist1", "wrist2", (0, 0.06, 0.05), (0, 0, 1)),
    ("wrist_3", "wrist2", "flange", (0, 0, 0.06), (0, 1, 0)),
]
ARM_JOINT_NAMES = [j[0] for j in ARM_JOINTS]
HOME = [0.0, 0.5, 1.0, 0.0, 0.8, 0.0]  # the wrist well away from the pan axis (a shoulder singularity)


def write_box_stl(path: Path, half: tuple[float, float, float]) -> None:
    """A binary STL box with half extents ``half`` centred at the origin."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) * half
    faces = [
        (0, 1, 3),
        (0, 3, 2),
        (4, 6, 7),
        (4, 7, 5),
        (0, 4, 5),
        (0, 5, 1),
        (2, 3, 7),
        (2, 7, 6),
        (0, 2, 6),
        (0, 6, 4),
        (1, 5, 7),
        (1, 7, 3),
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as out:
        out.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for face in faces:
            out.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for v in face:
                out.write(struct.pack("<3f", *corners[v]))
            out.write(b"\0\0")


def _inertial(mass: float, diag: tuple[float, float, float]) -> str:
    return (
        f'<inertial><mass value="{mass}"/><inertia ixx="{diag[0]}" iyy="{diag[1]}" izz="{diag[2]}" '
        f'ixy="0" ixz="0" iyz="0"/></inertial>'
    )


def _link(name: str, mesh: str | None, diag: tuple[float, float, float], mass: float = 1.0) -> str:
    geo = f'<geometry><mesh filename="{mesh}"/></geometry>' if mesh else ""
    shapes = f"<visual>{geo}</visual><collision>{geo}</collision>" if mesh else ""
    return f'<link name="{name}">{_inertial(mass, diag)}{shapes}</link>'


def write_urdf_arm(root: Path, unbalanced: bool = False, mesh_override: dict | None = None) -> Path:
    """Write ``root/test_arm/urdf/arm.urdf`` and its meshes; return the URDF path.

    Args:
        root: the folder to write into.
        unbalanced: give ``forearm`` an inertia breaking MuJoCo's ``A + B >= C``.
        mesh_override: link -> mesh filename written instead of the generated one.
    """
    pkg = root / "test_arm"
    links = ["base_link"] + [j[2] for j in ARM_JOINTS]
    parts = []
    for i, link in enumerate(links):
        write_box_stl(pkg / "meshes" / f"{link}.stl", (0.03, 0.03, 0.03 + 0.01 * i))
        mesh = f"package://test_arm/meshes/{link}.stl" if i % 2 == 0 else f"../meshes/{link}.stl"
        mesh = (mesh_override or {}).get(link, mesh)
        diag = (0.001, 0.001, 0.01) if unbalanced and link == "forearm" else (0.004, 0.004, 0.003)
        parts.append(_link(link, mesh, diag))
    parts += [
        _link("tool0", None, (1e-5, 1e-5, 1e-5), 0.01),
        _link("finger_left", None, (1e-5, 1e-5, 1e-5), 0.05),
        _link("finger_right", None, (1e-5, 1e-5, 1e-5), 0.05),
    ]
    for name, parent, child, xyz, axis in ARM_JOINTS:
        kind = "continuous" if name == "shoulder_pan" else "revolute"
        limit = "" if kind == "continuous" else '<limit lower="-3.0" upper="3.0" effort="150" velocity="3"/>'
        parts.append(
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{" ".join(map(str, xyz))}"/><axis xyz="{" ".join(map(str, axis))}"/>'
            f'{limit}<dynamics damping="0.5"/></joint>'
        )
    parts.append(
        '<joint name="tool_fixed" type="fixed"><parent link="flange"/><child link="tool0"/>'
        '<origin xyz="0 0.05 0"/></joint>'
    )
    for side, sign, mimic in (("left", 1, ""), ("right", -1, '<mimic joint="finger_left" multiplier="1"/>')):
        parts.append(
            f'<joint name="finger_{side}" type="prismatic"><parent link="tool0"/>'
            f'<child link="finger_{side}"/><origin xyz="{0.02 * sign} 0.03 0"/>'
            f'<axis xyz="{sign} 0 0"/><limit lower="0" upper="0.03" effort="20" velocity="0.1"/>'
            f"{mimic}</joint>"
        )
    path = pkg / "urdf" / "arm.urdf"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f'<robot name="test_arm">{"".join(parts)}</robot>')
    return path


def urdf_robot_section(path: Path, uid: str = "arm", **extra: object) -> dict:
    """A gym-config robot section for :func:`write_urdf_arm`'s arm, with an ``arm`` part."""
    section = {
        "uid": uid,
        "fpath": str(path),
        "init_qpos": HOME + [0.01, 0.01],
        "control_parts": {"arm": ARM_JOINT_NAMES, "gripper": ["finger_left"]},
        "drive_pros": {
            "stiffness": {"finger_.*": 500.0, "(?!finger_).*": 2000.0},
            "damping": {"finger_.*": 20.0, "(?!finger_).*": 100.0},
            "armature": {"finger_.*": 0.01, "(?!finger_).*": 0.05},
        },
    }  # rotor inertia: stable drives
    section.update(extra)
    return section


MJCF_ARM = """<mujoco model="servo_arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <inertial pos="0 0 0" mass="2" diaginertia="0.01 0.01 0.01"/>
      <geom type="cylinder" size="0.05 0.03"/>
      <body name="link1" pos="0 0 0.05">
        <joint name="j1" axis="0 0 1" range="-3 3" damping="1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03" mass="1"/>
        <body name="link2" pos="0 0 0.2">
          <joint name="j2" axis="0 1 0" range="-2 2" damping="1"/>
          <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025" mass="0.8"/>
          <body name="link3" pos="0.25 0 0">
            <joint name="j3" axis="0 1 0" range="-2 2" damping="1"/>
            <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/>
            <body name="hand" pos="0.2 0 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="servo1" joint="j1" kp="400" kv="20"/>
    <position name="servo2" joint="j2" kp="400" kv="20"/>
    <motor name="torque3" joint="j3" gear="1"/>
  </actuator>
</mujoco>
"""


def write_mjcf_arm(root: Path) -> Path:
    """Write the MJCF arm with its own actuators (two position servos, one motor)."""
    path = root / "servo_arm.xml"
    path.write_text(MJCF_ARM)
    return path
