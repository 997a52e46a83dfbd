"""Generate the asset pack deterministically (fixed seed, byte-exact writers).

Usage:
    python -m embodichain_assets.generate [--out DIR] [--check]

Without ``--out`` the files go to the package's own data folder (the one the plugin
registers). ``--check`` writes nothing and exits 1 when a file there differs from what the
generator produces (meshes and the URDF byte for byte, textures pixel for pixel).
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from embodichain_assets import DATA_ROOT, catalog, textures
from embodichain_assets.drawer import drawer_urdf
from embodichain_assets.writers import obj_bytes, ply_bytes, png_bytes


def _mesh_bytes(asset: catalog.MeshAsset) -> Callable[[], bytes]:
    """Producer of a mesh file's bytes (PLY, or OBJ by the name's suffix)."""

    def produce() -> bytes:
        part = asset.build()
        if asset.name.endswith(".obj"):
            return obj_bytes(part.vertices, part.faces, name=Path(asset.name).stem)
        return ply_bytes(part.vertices, part.faces)

    return produce


def _texture_png(index: int) -> bytes:
    return png_bytes(textures.texture(index))


def pack_files() -> dict[str, Callable[[], bytes]]:
    """Every file of the pack: data name -> function returning its bytes."""
    files: dict[str, Callable[[], bytes]] = {a.name: _mesh_bytes(a) for a in catalog.MESHES}
    files[catalog.DRAWER] = lambda: drawer_urdf().encode("utf-8")
    for i in range(textures.COUNT):
        name = f"{catalog.COCO_FOLDER}/{textures.texture_name(i)}"
        files[name] = functools.partial(_texture_png, i)
    return files


def generate(out: str | os.PathLike[str] | None = None, names: Sequence[str] | None = None) -> list[Path]:
    """Write the pack (or only ``names``) under ``out`` (default: the package data folder).

    Returns:
        The written paths, in catalogue order. Files are written atomically (temporary
        file + rename), so a reader never sees half a file.
    """
    root = Path(out) if out is not None else DATA_ROOT
    files = pack_files()
    written = []
    for name in names if names is not None else list(files):
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
        tmp.write_bytes(files[name]())
        os.replace(tmp, path)
        written.append(path)
    return written


def stale_files(root: str | os.PathLike[str] | None = None) -> list[str]:
    """Files under ``root`` (default: the data folder) that the generator does not produce."""
    base = Path(root) if root is not None else DATA_ROOT
    known = set(pack_files())
    found = sorted(p.relative_to(base).as_posix() for p in base.rglob("*") if p.is_file())
    return [name for name in found if name not in known]


def differing_files(root: str | os.PathLike[str] | None = None) -> list[str]:
    """Names whose file under ``root`` is missing or differs from the generator's output.

    PNGs that differ in bytes are compared pixel for pixel (a different zlib may compress the
    same image differently), see :func:`embodichain_assets.pngread.read_png`.
    """
    from embodichain_assets.pngread import read_png

    base = Path(root) if root is not None else DATA_ROOT
    out = []
    for name, produce in pack_files().items():
        path = base / name
        expected = produce()
        if not path.is_file():
            out.append(name)
        elif path.read_bytes() != expected:
            if not name.endswith(".png") or not np.array_equal(read_png(path.read_bytes()), read_png(expected)):
                out.append(name)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m embodichain_assets.generate", description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help=f"output folder (default: {DATA_ROOT})")
    parser.add_argument("--check", action="store_true", help="compare with the files in --out instead of writing")
    args = parser.parse_args(argv)
    root = Path(args.out) if args.out else DATA_ROOT
    if args.check:
        bad = differing_files(root)
        for name in bad:
            print(f"differs: {name}")
        print(f"{len(pack_files()) - len(bad)} of {len(pack_files())} files up to date in {root}")
        return 1 if bad else 0
    written = generate(root)
    size = sum(p.stat().st_size for p in written)
    print(f"wrote {len(written)} files ({size / 1e6:.2f} MB) to {root}")
    for name in stale_files(root):
        print(f"note: {name} is not produced by the generator (left in place)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
