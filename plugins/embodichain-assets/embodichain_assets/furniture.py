"""The two tables: ``CircleTableSimple`` (up = mesh -X) and ``ShopTableSimple`` (Z-up).

Each table is a union of closed convex parts (slab, pedestal or legs, base), so MuJoCo's
per-geom convex hulls are exact and no decomposition is needed.
"""

from __future__ import annotations

import numpy as np

from embodichain_assets.primitives import Part, box, cylinder, union

# CircleTableSimple, in table coordinates (Z up, origin at the centre of the top slab)
CIRCLE_TOP_RADIUS = 0.45
CIRCLE_TOP_THICKNESS = 0.04
CIRCLE_PEDESTAL_RADIUS = 0.05
CIRCLE_BASE_RADIUS = 0.25
CIRCLE_BASE_THICKNESS = 0.03
CIRCLE_HEIGHT_BELOW_TOP = 0.80  # slab centre to floor: placed at z = 0.8 the base touches z = 0

# Z-up design coordinates -> mesh coordinates in which up is -X: (x, y, z) -> (-z, y, x).
# EmbodiChain's init_rot=(0, 90, 0) (a +90 deg turn about Y) maps mesh -X back to +Z.
UP_IS_MINUS_X = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])

# ShopTableSimple (Z up, origin at the floor centre)
SHOP_TOP_SIZE = (0.60, 0.50, 0.04)
SHOP_HEIGHT = 0.80
SHOP_LEG_SIZE = 0.04
SHOP_LEG_XY = (0.26, 0.21)


def circle_table(segments: int = 64) -> Part:
    """The round table: a 0.45 m slab, a 0.05 m pedestal and a 0.25 m base disk.

    Built Z-up with the origin at the centre of the top slab (so its top surface is 0.02 above
    the origin), then turned so that up is mesh -X.
    """
    half = CIRCLE_TOP_THICKNESS / 2.0
    floor = -CIRCLE_HEIGHT_BELOW_TOP
    base_top = floor + CIRCLE_BASE_THICKNESS
    top = cylinder(CIRCLE_TOP_RADIUS, -half, half, segments)
    # the pedestal reaches 5 mm into the slab and the base: overlapping, never sharing a vertex
    pedestal = cylinder(CIRCLE_PEDESTAL_RADIUS, base_top - 0.005, -half + 0.005, segments // 2)
    base = cylinder(CIRCLE_BASE_RADIUS, floor, base_top, segments)
    return union([top, pedestal, base]).transformed(UP_IS_MINUS_X)


def shop_table() -> Part:
    """The rectangular table: a 0.60 x 0.50 x 0.04 top at z 0.76-0.80 and four 0.04 m legs."""
    sx, sy, sz = SHOP_TOP_SIZE
    top = box((0.0, 0.0, SHOP_HEIGHT - sz / 2.0), SHOP_TOP_SIZE)
    leg_height = SHOP_HEIGHT - sz
    legs = [
        box((x, y, leg_height / 2.0), (SHOP_LEG_SIZE, SHOP_LEG_SIZE, leg_height))
        for x in (-SHOP_LEG_XY[0], SHOP_LEG_XY[0])
        for y in (-SHOP_LEG_XY[1], SHOP_LEG_XY[1])
    ]
    return union([top, *legs])
