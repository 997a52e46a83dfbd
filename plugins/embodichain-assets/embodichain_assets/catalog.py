"""What the pack contains: every asset's data name, how to build it and a one-line description.

The data names mirror EmbodiChain's ``get_data_path`` keys, so configs copied from EmbodiChain
resolve unchanged.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

from embodichain_assets import furniture, objects, tableware
from embodichain_assets.primitives import Part

CIRCLE_TABLE = "CircleTableSimple/circle_table_simple.ply"
SHOP_TABLE = "ShopTableSimple/shop_table_simple.ply"
FORK_FOLDER = "TableWare/tableware/fork/"
STANDARD_FORK = FORK_FOLDER + "standard_fork_scale.ply"
DRAWER = "SlidingBoxDrawer/SlidingBoxDrawer.urdf"
COCO_FOLDER = "CocoBackground/coco"
PAPER_CUP = "PaperCup/paper_cup.ply"
MUG = "CoffeeCup/cup.ply"
SODA_CAN = "SodaCan/simple_cola_can.obj"
CUBE = "Cube/cube.ply"


@dataclass(frozen=True)
class MeshAsset:
    """A mesh file of the pack.

    Attributes:
        name: the data name (path under the data root).
        build: returns the mesh.
        description: one line for the docs.
        convex_parts: every connected component is convex (no decomposition needed).
    """

    name: str
    build: Callable[[], Part]
    description: str
    convex_parts: bool = True


def _fork_assets() -> list[MeshAsset]:
    out = []
    for file, spec in tableware.FORKS.items():
        extra = ", handle raised 15 mm" if spec.handle_rise else ""
        extra += ", wide cutting tine" if spec.wide_first_tine else ""
        out.append(
            MeshAsset(
                FORK_FOLDER + file,
                functools.partial(tableware.fork, spec),
                f"fork, {spec.length * 100:.0f} cm, {spec.tines} tines, head {spec.head_width * 1000:.0f} mm{extra}",
            )
        )
    return out


MESHES: list[MeshAsset] = [
    MeshAsset(
        CIRCLE_TABLE,
        furniture.circle_table,
        "round table r 0.45 m, up = mesh -X, origin at the top slab centre (top surface 0.02 above)",
    ),
    MeshAsset(
        SHOP_TABLE,
        furniture.shop_table,
        "rectangular table, Z-up, origin at the floor centre, top 0.60 x 0.50 m at z 0.76-0.80",
    ),
    *_fork_assets(),
    MeshAsset(PAPER_CUP, objects.paper_cup, "paper cup: frustum r 0.025-0.035 m, 0.09 m high, origin at the bottom"),
    MeshAsset(
        MUG,
        objects.mug,
        "mug r 0.04 m, 0.09 m high, convex body + non-convex half-ring handle on +X",
        convex_parts=False,
    ),
    MeshAsset(SODA_CAN, objects.soda_can, "soda can r 0.033 m, 0.122 m high, chamfered edges (OBJ)"),
    MeshAsset(CUBE, objects.cube, "5 cm cube centred at the origin"),
]


def mesh_asset(name: str) -> MeshAsset:
    """The :class:`MeshAsset` called ``name``.

    Raises:
        KeyError: no such mesh in the pack.
    """
    for asset in MESHES:
        if asset.name == name:
            return asset
    raise KeyError(f"no mesh {name!r} in the pack; meshes: {[a.name for a in MESHES]}")
