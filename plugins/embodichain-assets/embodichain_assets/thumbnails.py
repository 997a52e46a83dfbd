"""Render a thumbnail of every asset (offscreen, ``mujoco.Renderer``), for docs/asset_pack.md.

Each asset is loaded through the core's scene builder (``Scene`` + ``get_data_path``), exactly
as a config would load it, so a thumbnail also shows that the asset resolves, loads and
compiles. Textures are shown as one contact sheet.

Usage:
    python -m embodichain_assets.thumbnails [--out docs/images] [--size 400 300]
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from embodichain_assets import catalog, textures
from embodichain_assets.writers import png_bytes


@dataclass
class Shot:
    """How to show one asset: its pose, colour and the camera."""

    init_pos: tuple = (0.0, 0.0, 0.0)
    init_rot: tuple = (0.0, 0.0, 0.0)
    color: tuple = (0.75, 0.75, 0.78, 1.0)
    texture: str | None = None
    azimuth: float = 135.0
    elevation: float = -30.0
    zoom: float = 1.6
    extra: dict = field(default_factory=dict)


WOOD_TEXTURE = f"{catalog.COCO_FOLDER}/{textures.texture_name(5)}"
SHOTS: dict[str, Shot] = {
    catalog.CIRCLE_TABLE: Shot((0.0, 0.0, 0.8), (0.0, 90.0, 0.0), (1, 1, 1, 1), WOOD_TEXTURE, elevation=-25, zoom=1.3),
    catalog.SHOP_TABLE: Shot(color=(0.78, 0.62, 0.42, 1.0), elevation=-25, zoom=1.3),
    catalog.PAPER_CUP: Shot(color=(0.95, 0.95, 0.92, 1.0), elevation=-30),
    catalog.MUG: Shot(color=(0.25, 0.45, 0.8, 1.0), azimuth=120, elevation=-30),
    catalog.SODA_CAN: Shot(color=(0.85, 0.1, 0.12, 1.0), elevation=-30),
    catalog.CUBE: Shot((0.0, 0.0, 0.025), color=(0.95, 0.55, 0.1, 1.0)),
}
FORK_SHOT = Shot((0.0, 0.0, 0.012), color=(0.85, 0.85, 0.9, 1.0), azimuth=90, elevation=-70, zoom=1.15)


def slug(name: str) -> str:
    """Thumbnail name of an asset: ``asset_<file stem in snake case>`` (``asset_cup`` for the mug)."""
    stem = Path(name.rstrip("/")).stem
    return "asset_" + re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", stem).lower()


def _scene(shot: Shot, name: str | None = None, urdf: str | None = None) -> Any:
    """A one-env scene with the asset (a kinematic mesh object, or an articulation) and a light."""
    from embodichain_core.sim.cfg import ArticulationCfg, LightCfg, RigidObjectCfg, SimulationManagerCfg
    from embodichain_core.sim.scene import Scene
    from embodichain_core.sim.shapes import MeshCfg, VisualMaterialCfg

    scene = Scene(SimulationManagerCfg(width=640, height=480), num_envs=1)
    if name is not None:
        material = VisualMaterialCfg(base_color=shot.color, base_color_texture=shot.texture)
        shape = MeshCfg(fpath=name, compute_uv=shot.texture is not None, visual_material=material)
        scene.add_rigid_object(
            RigidObjectCfg(
                uid="asset", shape=shape, body_type="kinematic", init_pos=shot.init_pos, init_rot=shot.init_rot
            ),
            background=True,
        )
    if urdf is not None:
        scene.add_articulation(ArticulationCfg(uid="asset", fpath=urdf, init_pos=shot.init_pos))
    scene.add_light(LightCfg(uid="key", light_type="point", intensity=30.0, init_pos=(1.0, -1.5, 3.0)))
    scene.build()
    return scene


def render_scene(scene: Any, shot: Shot, size: Sequence[int], lookat: np.ndarray, extent: float) -> np.ndarray:
    """Render env 0 of ``scene`` with a free camera looking at ``lookat`` from ``extent * zoom``."""
    import mujoco

    data = scene.sim.get_data(0)
    mujoco.mj_forward(scene.model, data)
    camera = mujoco.MjvCamera()
    camera.type = mujoco.mjtCamera.mjCAMERA_FREE
    camera.lookat[:] = lookat
    camera.distance = max(extent * shot.zoom, 0.12)
    camera.azimuth, camera.elevation = shot.azimuth, shot.elevation
    with mujoco.Renderer(scene.model, height=int(size[1]), width=int(size[0])) as renderer:
        renderer.update_scene(data, camera=camera)
        return renderer.render().copy()


def _mesh_thumbnail(name: str, shot: Shot, size: Sequence[int]) -> np.ndarray:
    """Load mesh ``name`` into a scene and frame its world bounding box."""
    scene = _scene(shot, name=name)
    data = scene.sim.get_data(0)
    lo, hi = _geom_bounds(scene.model, data, "asset/visual")
    return render_scene(scene, shot, size, (lo + hi) / 2.0, float(np.linalg.norm(hi - lo)))


def _geom_bounds(model: Any, data: Any, geom_name: str) -> tuple[np.ndarray, np.ndarray]:
    """World bounding box of a mesh geom's vertices."""
    import mujoco

    mujoco.mj_forward(model, data)
    geom = model.geom(geom_name).id
    mesh = int(model.geom_dataid[geom])
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    local = model.mesh_vert[start : start + count].astype(float)
    world = local @ data.geom_xmat[geom].reshape(3, 3).T + data.geom_xpos[geom]
    return world.min(axis=0), world.max(axis=0)


def _drawer_thumbnail(size: Sequence[int], opening: float = 0.12) -> np.ndarray:
    """The drawer on the floor, opened by ``opening`` metres."""
    shot = Shot(azimuth=210.0, elevation=-25.0, zoom=1.5)
    scene = _scene(shot, urdf=catalog.DRAWER)
    scene["asset"].set_qpos([[opening]], target=False)
    scene.sim.forward()
    return render_scene(scene, shot, size, np.array([0.08, 0.0, 0.1]), 0.55)


def _seed_scene_thumbnail(size: Sequence[int], steps: int = 150) -> np.ndarray:
    """The seed tutorial's scene after the fork has settled on the table."""
    from embodichain_assets.seed_scene import build_seed_scene

    scene = build_seed_scene()
    scene.sim.step(steps)
    scene.model.mat_rgba[scene.model.material("table/mat").id] = [0.8, 0.68, 0.52, 1.0]  # contrast with the fork
    shot = Shot(azimuth=230.0, elevation=-45.0, zoom=1.0)
    return render_scene(scene, shot, size, np.array([0.72, 0.0, 0.86]), 0.75)


def coco_sheet(columns: int = 8, tile: int = 64) -> np.ndarray:
    """All background textures, downsampled, in a ``columns``-wide grid."""
    step = max(1, textures.SIZE // tile)
    tiles = [textures.texture(i)[::step, ::step] for i in range(textures.COUNT)]
    rows = [np.concatenate(tiles[r : r + columns], axis=1) for r in range(0, len(tiles), columns)]
    return np.concatenate(rows, axis=0)


def render_all(out: str | os.PathLike[str], size: Sequence[int] = (400, 300)) -> list[Path]:
    """Write every thumbnail to ``out``; return the paths."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    images: dict[str, np.ndarray] = {}
    for asset in catalog.MESHES:
        shot = FORK_SHOT if asset.name.startswith(catalog.FORK_FOLDER) else SHOTS[asset.name]
        images[slug(asset.name)] = _mesh_thumbnail(asset.name, shot, size)
    images[slug(catalog.DRAWER)] = _drawer_thumbnail(size)
    images["asset_coco_background"] = coco_sheet()
    images["asset_seed_scene"] = _seed_scene_thumbnail(size)
    paths = []
    for stem, image in images.items():
        path = folder / f"{stem}.png"
        path.write_bytes(png_bytes(image))
        paths.append(path)
    return paths


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point (see the module docstring)."""
    parser = argparse.ArgumentParser(
        prog="python -m embodichain_assets.thumbnails", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--out", default="docs/images", help="output folder (default: docs/images)")
    parser.add_argument("--size", type=int, nargs=2, default=(400, 300), metavar=("W", "H"))
    args = parser.parse_args(argv)
    os.environ.setdefault("MUJOCO_GL", "egl")
    for path in render_all(args.out, args.size):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
