"""Fork variants of ``TableWare/tableware/fork/``: unions of boxes, one convex part each.

A fork lies along X (handle toward -X, tines toward +X), its width along Y and its thickness
along Z, with the origin at the centre of its bounding box. Parts overlap by about a millimetre
and differ in thickness, so no two parts share a vertex position: every part stays its own
connected, convex component.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from embodichain_assets.primitives import Part, box, rot_y, union

HEAD_LENGTH = 0.020
NECK_LENGTH = 0.030
NECK_WIDTH = 0.010
HANDLE_THICKNESS = 0.005
HEAD_THICKNESS = 0.0045
TINE_THICKNESS = 0.004
OVERLAP = 0.001


@dataclass(frozen=True)
class ForkSpec:
    """Dimensions of one fork (metres)."""

    length: float
    tines: int
    tine_length: float
    head_width: float = 0.026
    handle_width: float = 0.016
    tine_width: float = 0.004
    handle_rise: float = 0.0
    wide_first_tine: bool = False


FORKS: dict[str, ForkSpec] = {
    "standard_fork_scale.ply": ForkSpec(length=0.19, tines=4, tine_length=0.040),
    "fork_three_tine.ply": ForkSpec(length=0.17, tines=3, tine_length=0.036, head_width=0.024, tine_width=0.0045),
    "fork_long.ply": ForkSpec(length=0.21, tines=4, tine_length=0.045, handle_width=0.018),
    "fork_salad.ply": ForkSpec(
        length=0.16, tines=4, tine_length=0.032, head_width=0.030, handle_width=0.014, tine_width=0.005
    ),
    "fork_cake.ply": ForkSpec(
        length=0.14, tines=3, tine_length=0.028, head_width=0.022, handle_width=0.012, wide_first_tine=True
    ),
    "fork_bent.ply": ForkSpec(length=0.19, tines=4, tine_length=0.040, handle_rise=0.015),
}


def fork(spec: ForkSpec) -> Part:
    """The fork described by ``spec``, centred at its bounding-box centre."""
    x0 = -spec.length / 2.0
    handle_len = spec.length - spec.tine_length - HEAD_LENGTH - NECK_LENGTH
    neck_x = x0 + handle_len
    head_x = neck_x + NECK_LENGTH
    parts = _handle(x0, handle_len, spec) + [_neck(neck_x, spec)]
    parts.append(box((head_x + HEAD_LENGTH / 2.0, 0.0, 0.0), (HEAD_LENGTH, spec.head_width, HEAD_THICKNESS)))
    parts += _tines(head_x + HEAD_LENGTH - OVERLAP, spec)
    mesh = union(parts)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    return mesh.transformed(offset=-(lo + hi) / 2.0)


def _handle(x0: float, length: float, spec: ForkSpec) -> list[Part]:
    """The handle bar and a slightly wider grip end, raised by ``handle_rise``."""
    z = spec.handle_rise
    bar = box((x0 + OVERLAP + length / 2.0, 0.0, z), (length, spec.handle_width, HANDLE_THICKNESS))
    grip_len = min(0.03, length / 3.0)
    grip = box((x0 + grip_len / 2.0, 0.0, z), (grip_len, spec.handle_width * 1.2, HANDLE_THICKNESS * 0.9))
    return [bar, grip]


def _neck(x: float, spec: ForkSpec) -> Part:
    """The neck from the handle to the head plate; sloped when the handle is raised."""
    rise = spec.handle_rise
    run = NECK_LENGTH + 2.0 * OVERLAP
    length = float(np.hypot(run, rise))
    angle = float(np.degrees(np.arctan2(rise, run)))
    centre = (x + NECK_LENGTH / 2.0, 0.0, rise / 2.0)
    return box(centre, (length, NECK_WIDTH, HANDLE_THICKNESS * 0.85), rot_y(angle) if rise else None)


def _tines(x: float, spec: ForkSpec) -> list[Part]:
    """``spec.tines`` tines spread over the head width; a cake fork's first tine is wider."""
    widths = np.full(spec.tines, spec.tine_width)
    if spec.wide_first_tine:
        widths[0] = spec.tine_width * 2.0
    gap = (spec.head_width - widths.sum()) / (spec.tines - 1)
    y = -spec.head_width / 2.0
    parts = []
    for width in widths:
        centre = (x + (spec.tine_length + OVERLAP) / 2.0, y + width / 2.0, 0.0)
        parts.append(box(centre, (spec.tine_length + OVERLAP, width, TINE_THICKNESS)))
        y += width + gap
    return parts


def all_forks() -> dict[str, Part]:
    """Every fork variant by file name."""
    return {name: fork(spec) for name, spec in FORKS.items()}
