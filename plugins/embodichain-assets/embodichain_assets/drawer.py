"""``SlidingBoxDrawer/SlidingBoxDrawer.urdf``: a box with a sliding drawer, primitives only.

* ``outer_box`` (root, 3 kg): bottom, top, back and side plates 0.01 thick, outer 0.36 (depth,
  X) x 0.40 (width, Y) x 0.20 m, origin at the bottom centre, open toward +X.
* ``inner_drawer`` (0.5 kg): a 0.32 x 0.36 x 0.15 m tray with a front panel, on the prismatic
  joint ``slide_rails`` along +X, limits [0, 0.2] m, damping 1, friction 0.05.
* ``handle_xpos``: fixed to the front panel, a 0.12 m bar on 2.5 cm posts; its frame sits at the
  bar centre with rpy (0, -pi/2, 0), so its +Z points into the drawer (pull along -Z to open).

Depth 0.36 m and 2.5 cm posts (the research notes estimated 0.40 m and 3 cm) keep the closed
drawer's handle at x <= 0.215 m from its origin: in the seed tutorial's scene (drawer at x 0.5,
forks dropped at x 0.8 with a 0.75 scale) the handle then stays clear of every fork variant.

The ``<mujoco><compiler fusestatic="false" discardvisual="false"/></mujoco>`` block keeps the
fixed link ``handle_xpos`` as a body in MuJoCo's URDF importer (it would be fused otherwise).
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

JOINT_Z = 0.012  # drawer frame above the outer box's origin
SLIDE_LIMIT = (0.0, 0.2)
OUTER_SIZE = (0.36, 0.40, 0.20)  # depth (x) x width (y) x height (z)
TRAY_SIZE = (0.32, 0.36, 0.15)
POST_LENGTH = 0.025
HANDLE_POS = (0.21, 0.0, 0.11)  # bar centre in the drawer frame: panel face 0.18 + posts + half bar
HANDLE_RPY = (0.0, -1.5707963267948966, 0.0)

MATERIALS = {
    "wood_dark": (0.42, 0.28, 0.17, 1.0),
    "wood_light": (0.78, 0.62, 0.42, 1.0),
    "metal": (0.72, 0.73, 0.75, 1.0),
}


class Plate(NamedTuple):
    """A box geom of a link: name, centre, full size and material name."""

    name: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    material: str


OUTER = [
    Plate("bottom", (0.0, 0.0, 0.005), (0.36, 0.40, 0.01), "wood_dark"),
    Plate("top", (0.0, 0.0, 0.195), (0.36, 0.40, 0.01), "wood_dark"),
    Plate("back", (-0.175, 0.0, 0.10), (0.01, 0.40, 0.18), "wood_dark"),
    Plate("left", (0.005, 0.195, 0.10), (0.35, 0.01, 0.18), "wood_dark"),
    Plate("right", (0.005, -0.195, 0.10), (0.35, 0.01, 0.18), "wood_dark"),
]
INNER = [  # in the drawer frame (JOINT_Z above the outer box's origin, closed at q = 0)
    Plate("tray_bottom", (0.01, 0.0, 0.004), (0.32, 0.36, 0.008), "wood_light"),
    Plate("tray_back", (-0.146, 0.0, 0.075), (0.008, 0.36, 0.15), "wood_light"),
    Plate("tray_left", (0.01, 0.176, 0.075), (0.32, 0.008, 0.15), "wood_light"),
    Plate("tray_right", (0.01, -0.176, 0.075), (0.32, 0.008, 0.15), "wood_light"),
    Plate("front_panel", (0.175, 0.0, 0.085), (0.01, 0.378, 0.17), "wood_dark"),
]
HANDLE = [  # in the handle frame: X = drawer up, Y = drawer Y, Z = into the drawer
    Plate("bar", (0.0, 0.0, 0.0), (0.01, 0.12, 0.01), "metal"),
    Plate("post_left", (0.0, 0.05, 0.005 + POST_LENGTH / 2), (0.01, 0.01, POST_LENGTH), "metal"),
    Plate("post_right", (0.0, -0.05, 0.005 + POST_LENGTH / 2), (0.01, 0.01, POST_LENGTH), "metal"),
]


def _fmt(values: Sequence[float]) -> str:
    return " ".join(f"{v:.9g}" for v in values)


def _box_inertia(mass: float, size: Sequence[float]) -> str:
    """``<inertia>`` of a solid box of ``size`` (a fair stand-in for a hollow link)."""
    x, y, z = size
    ixx, iyy, izz = (mass / 12.0 * (b * b + c * c) for b, c in ((y, z), (x, z), (x, y)))
    return f'<inertia ixx="{ixx:.6g}" ixy="0" ixz="0" iyy="{iyy:.6g}" iyz="0" izz="{izz:.6g}"/>'


def _link(name: str, mass: float, com: Sequence[float], extent: Sequence[float], plates: list[Plate]) -> str:
    """A ``<link>`` with an inertial and one visual and one collision element per plate."""
    out = [
        f'  <link name="{name}">',
        f'    <inertial><origin xyz="{_fmt(com)}" rpy="0 0 0"/><mass value="{mass:g}"/>'
        f"{_box_inertia(mass, extent)}</inertial>",
    ]
    for p in plates:
        geo = f'<origin xyz="{_fmt(p.center)}" rpy="0 0 0"/><geometry><box size="{_fmt(p.size)}"/></geometry>'
        out.append(f'    <visual name="{p.name}_visual">{geo}<material name="{p.material}"/></visual>')
        out.append(f'    <collision name="{p.name}">{geo}</collision>')
    out.append("  </link>")
    return "\n".join(out)


def drawer_urdf() -> str:
    """The URDF text of the sliding drawer."""
    materials = [f'  <material name="{n}"><color rgba="{_fmt(c)}"/></material>' for n, c in MATERIALS.items()]
    parts = [
        '<?xml version="1.0"?>',
        '<robot name="SlidingBoxDrawer">',
        '  <mujoco>\n    <compiler fusestatic="false" discardvisual="false"/>\n  </mujoco>',
        *materials,
        _link("outer_box", 3.0, (0.0, 0.0, 0.10), OUTER_SIZE, OUTER),
        _link("inner_drawer", 0.5, (0.01, 0.0, 0.075), TRAY_SIZE, INNER),
        _link("handle_xpos", 0.05, (0.0, 0.0, 0.0), (0.01, 0.12, 0.01), HANDLE),
        '  <joint name="slide_rails" type="prismatic">',
        '    <parent link="outer_box"/>\n    <child link="inner_drawer"/>',
        f'    <origin xyz="0 0 {JOINT_Z:g}" rpy="0 0 0"/>\n    <axis xyz="1 0 0"/>',
        f'    <limit lower="{SLIDE_LIMIT[0]:g}" upper="{SLIDE_LIMIT[1]:g}" effort="100" velocity="1"/>',
        '    <dynamics damping="1.0" friction="0.05"/>',
        "  </joint>",
        '  <joint name="handle_joint" type="fixed">',
        '    <parent link="inner_drawer"/>\n    <child link="handle_xpos"/>',
        f'    <origin xyz="{_fmt(HANDLE_POS)}" rpy="{_fmt(HANDLE_RPY)}"/>',
        "  </joint>",
        "</robot>",
    ]
    return "\n".join(parts) + "\n"
