"""Graspable objects: paper cup, mug, soda can and cube (Z-up; cups and can from the bottom).

The mug's handle is the one deliberately non-convex part of the pack: a half ring. With the
default ``max_convex_hull_num=1`` it collides as its convex hull (a closed D-shaped slab); with
``max_convex_hull_num > 1`` coacd opens the loop (cached on disk after the first build).
Everything else is one convex component per part.
"""

from __future__ import annotations

from embodichain_assets.primitives import Part, box, revolve, tube_arc, union

PAPER_CUP = {"r_bottom": 0.025, "r_top": 0.035, "height": 0.09}
MUG = {"radius": 0.04, "height": 0.09, "handle_major": 0.03, "handle_minor": 0.006}
SODA_CAN = {"radius": 0.033, "height": 0.122}
CUBE_SIZE = 0.05


def paper_cup(segments: int = 48) -> Part:
    """A frustum: radius 0.025 at the bottom, 0.035 at the top, 0.09 high (convex)."""
    p = PAPER_CUP
    return revolve([(p["r_bottom"], 0.0), (p["r_top"], p["height"])], segments)


def mug(segments: int = 48) -> Part:
    """A 0.04 m x 0.09 m mug: a convex body with a bevelled foot, and a half-ring handle on +X.

    The handle's ends sink into the body wall, so body and handle are two separate connected
    components (convex body, non-convex handle).
    """
    r, h = MUG["radius"], MUG["height"]
    body = revolve([(r - 0.004, 0.0), (r, 0.004), (r, h)], segments)
    handle = tube_arc(MUG["handle_major"], MUG["handle_minor"], -100.0, 100.0, segments=24, sides=12)
    handle = handle.transformed(offset=(r - 0.005, 0.0, h / 2.0))
    return union([body, handle])


def soda_can(segments: int = 48) -> Part:
    """A 0.033 m x 0.122 m can with chamfered bottom and top edges (convex)."""
    r, h = SODA_CAN["radius"], SODA_CAN["height"]
    return revolve([(r - 0.006, 0.0), (r, 0.008), (r, h - 0.010), (r - 0.005, h)], segments)


def cube() -> Part:
    """A 0.05 m cube centred at the origin."""
    return box((0.0, 0.0, 0.0), (CUBE_SIZE,) * 3)
