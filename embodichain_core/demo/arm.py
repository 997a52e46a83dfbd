"""Generator of the demo's 7-DoF arm (``arm7.xml``): seven hinge joints and a
two-finger gripper whose second finger mimics the first (a joint equality).

The shipped ``arm7.xml`` is this module's output; regenerate it with
``python -m embodichain_core.demo.arm``.

Example:
    >>> xml = arm7_mjcf()
    >>> xml.count("<joint ")
    9
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional, Sequence

__all__ = ["ARM7_PATH", "JOINT_AXES", "arm7_mjcf", "write_arm7"]

#: Where the shipped model lives (next to this module).
ARM7_PATH = Path(__file__).with_name("arm7.xml")
#: Hinge axis of each arm joint, base to wrist.
JOINT_AXES = ("0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1")

_LINK_RGBA = ("0.85 0.85 0.88 1", "0.95 0.55 0.15 1")
_HAND = """\
{pad}<body name="hand" pos="0 0 0.1">
{pad}  <geom type="box" size="0.02 0.06 0.02" mass="0.3" rgba="0.2 0.2 0.22 1"/>
{pad}  <site name="tcp" pos="0 0 0.07" size="0.005"/>
{pad}  <body name="finger_l" pos="0 0.02 0.04">
{pad}    <joint name="finger_joint1" type="slide" axis="0 1 0" range="0 0.04"/>
{pad}    <geom type="box" size="0.01 0.01 0.03" mass="0.05" rgba="0.2 0.2 0.22 1"/>
{pad}  </body>
{pad}  <body name="finger_r" pos="0 -0.02 0.04">
{pad}    <joint name="finger_joint2" type="slide" axis="0 -1 0" range="0 0.04"/>
{pad}    <geom type="box" size="0.01 0.01 0.03" mass="0.05" rgba="0.2 0.2 0.22 1"/>
{pad}  </body>
{pad}</body>
"""


def _link(index: int, axis: str, pad: str, limit: float) -> str:
    """Opening lines of link ``index`` (1-based): body, hinge joint, capsule geom."""
    z = 0.08 if index == 1 else 0.1
    rgba = _LINK_RGBA[index % 2]
    return (
        f'{pad}<body name="link{index}" pos="0 0 {z}">\n'
        f'{pad}  <joint name="joint{index}" type="hinge" axis="{axis}" range="{-limit} {limit}"/>\n'
        f'{pad}  <geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.04" mass="1" rgba="{rgba}"/>\n'
    )


def arm7_mjcf(name: str = "arm7", joint_limit: float = 2.8) -> str:
    """The MJCF text of the arm.

    Args:
        name: the model name.
        joint_limit: symmetric range of every arm hinge, in radians.

    Returns:
        A complete ``<mujoco>`` document (joints ``joint1..7``, ``finger_joint1/2``).
    """
    lines = [
        f'<mujoco model="{name}">',
        '  <compiler angle="radian"/>',
        "  <worldbody>",
        '    <body name="base">',
        '      <geom type="cylinder" size="0.08 0.04" mass="5" rgba="0.3 0.3 0.32 1"/>',
    ]
    body = ""
    for i, axis in enumerate(JOINT_AXES):
        body += _link(i + 1, axis, "      " + "  " * i, joint_limit)
    pad = "      " + "  " * len(JOINT_AXES)
    body += _HAND.format(pad=pad)
    for i in reversed(range(len(JOINT_AXES))):
        body += "      " + "  " * i + "</body>\n"
    lines += [
        body.rstrip("\n"),
        "    </body>",
        "  </worldbody>",
        "  <equality>",
        '    <joint joint1="finger_joint2" joint2="finger_joint1" polycoef="0 1 0 0 0"/>',
        "  </equality>",
        "</mujoco>",
    ]
    return "\n".join(lines) + "\n"


def write_arm7(path: Optional[Path] = None) -> Path:
    """Write :func:`arm7_mjcf` to ``path`` (default: the shipped ``arm7.xml``)."""
    target = Path(path) if path is not None else ARM7_PATH
    target.write_text(arm7_mjcf(), encoding="utf-8")
    return target


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``python -m embodichain_core.demo.arm [PATH]``: (re)generate the model file."""
    args = list(sys.argv[1:] if argv is None else argv)
    print(write_arm7(Path(args[0]) if args else None))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
