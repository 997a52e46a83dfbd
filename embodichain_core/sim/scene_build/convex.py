"""Collision geometry: convex parts of a mesh, with coacd and an on-disk cache.

MuJoCo collides with the convex hull of each mesh geom. :func:`collision_parts` returns convex
pieces that together approximate a mesh: its connected components that are already convex are
kept as they are; a non-convex component becomes its convex hull (``max_convex_hull_num=1``)
or is decomposed with coacd into at most ``max_convex_hull_num`` hulls. coacd results are cached
in ``$EMBODICHAIN_CACHE_DIR/coacd`` (default ``~/.cache/embodichain/coacd``) under a hash of the
mesh and the parameters, so only the first build pays.

Example:
    >>> parts = collision_parts(load_mesh("mug.ply"), max_convex_hull_num=8)  # doctest: +SKIP
"""

from __future__ import annotations

import functools
import importlib.metadata
import os
import time
import uuid
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from embodichain_core.sim.scene_build.mesh import MeshData, convex_hull, is_convex, mesh_hash, split_components

ENV_CACHE_DIR = "EMBODICHAIN_CACHE_DIR"
METHODS = ("coacd", "hull")
DEFAULT_THRESHOLD = 0.05
SEED = 0
_CACHE_FORMAT = 1


@dataclass
class Decomposition:
    """Result of :func:`decompose`.

    Attributes:
        parts: convex meshes, one collision geom each.
        components: number of connected components of the input.
        convex_components: how many of them were convex already.
        cached: the parts came from the disk cache.
        seconds: wall time spent.
    """

    parts: list[MeshData]
    components: int
    convex_components: int
    cached: bool = False
    seconds: float = 0.0


@dataclass
class MeshReport:
    """One row of a :class:`DecompositionReport`."""

    mesh: str
    components: int
    convex_components: int
    hulls: int
    cached: bool
    seconds: float


@dataclass
class DecompositionReport:
    """What :func:`decompose_file` did for each mesh of a file."""

    path: str
    rows: list[MeshReport] = field(default_factory=list)

    def format_table(self) -> str:
        """A plain-text table: mesh, components, convex components, hulls, cached, time."""
        header = ("mesh", "components", "convex", "hulls", "cached", "time [s]")
        lines = [
            (
                r.mesh,
                str(r.components),
                str(r.convex_components),
                str(r.hulls),
                "yes" if r.cached else "no",
                f"{r.seconds:.3f}",
            )
            for r in self.rows
        ]
        widths = [max(len(row[i]) for row in [header, *lines]) for i in range(len(header))]
        fmt = lambda row: "  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip()  # noqa: E731
        return "\n".join([fmt(header), fmt(tuple("-" * w for w in widths)), *map(fmt, lines)])


def cache_root(cache_dir: str | os.PathLike[str] | None = None) -> str:
    """The coacd cache folder: ``cache_dir``, ``$EMBODICHAIN_CACHE_DIR/coacd`` or the default."""
    if cache_dir is not None:
        return os.path.abspath(os.path.expanduser(os.fspath(cache_dir)))
    base = os.environ.get(ENV_CACHE_DIR) or os.path.join("~", ".cache", "embodichain")
    return os.path.join(os.path.abspath(os.path.expanduser(base)), "coacd")


def collision_parts(
    mesh: MeshData,
    max_convex_hull_num: int = 1,
    method: str = "coacd",
    cache_dir: str | os.PathLike[str] | None = None,
    threshold: float = DEFAULT_THRESHOLD,
) -> list[MeshData]:
    """Convex meshes approximating ``mesh`` for collision (see :func:`decompose`)."""
    return decompose(mesh, max_convex_hull_num, method, cache_dir, threshold).parts


def decompose(
    mesh: MeshData,
    max_convex_hull_num: int = 1,
    method: str = "coacd",
    cache_dir: str | os.PathLike[str] | None = None,
    threshold: float = DEFAULT_THRESHOLD,
) -> Decomposition:
    """Split ``mesh`` into convex collision parts.

    Args:
        mesh: the mesh.
        max_convex_hull_num: most hulls per non-convex component; 1 uses its convex hull.
        method: ``"coacd"`` (decompose non-convex components) or ``"hull"`` (always hull them).
        cache_dir: where coacd results go (default: see :func:`cache_root`).
        threshold: coacd concavity threshold.

    Returns:
        The parts and what was done; coacd runs at most once per mesh and parameters.
    """
    if method not in METHODS:
        from embodichain_core.utils.suggest import did_you_mean

        raise ValueError(f"unknown decomposition method {method!r}.{did_you_mean(method, METHODS)}")
    if max_convex_hull_num < 1:
        raise ValueError(f"max_convex_hull_num must be >= 1, got {max_convex_hull_num}")
    start = time.perf_counter()
    use_coacd = method == "coacd" and max_convex_hull_num > 1
    key = mesh_hash(
        mesh,
        method=method,
        n=max_convex_hull_num,
        threshold=threshold,
        seed=SEED,
        format=_CACHE_FORMAT,
        coacd=_coacd_version() if use_coacd else "",
    )
    cache_file = os.path.join(cache_root(cache_dir), key[:2], key + ".npz")
    if use_coacd:
        hit = _load_cache(cache_file)
        if hit is not None:
            hit.seconds = time.perf_counter() - start
            return hit
    components = split_components(mesh)
    convex = [is_convex(c) for c in components]
    parts: list[MeshData] = []
    for comp, ok in zip(components, convex):
        parts.extend(_convex_pieces(comp, ok, max_convex_hull_num if use_coacd else 1, threshold))
    result = Decomposition(parts, len(components), sum(convex))
    if use_coacd and not all(convex):
        _save_cache(cache_file, result)
    result.seconds = time.perf_counter() - start
    return result


def _convex_pieces(component: MeshData, convex: bool, max_hulls: int, threshold: float) -> list[MeshData]:
    """A convex component as is; else coacd (``max_hulls > 1``) or the convex hull."""
    if convex:
        return [component]
    if max_hulls > 1:
        return _run_coacd(component, max_hulls, threshold, SEED)
    try:
        return [convex_hull(component)]
    except ValueError:  # degenerate: MuJoCo hulls (or rejects) it itself
        return [component]


@functools.lru_cache(maxsize=1)
def _coacd_version() -> str:
    """The installed coacd version (part of the cache key), or ``""``."""
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return ""


def _run_coacd(mesh: MeshData, max_convex_hull: int, threshold: float, seed: int) -> list[MeshData]:
    """Run coacd on one component (the seam tests patch to count calls)."""
    import coacd

    coacd.set_log_level("error")
    result = coacd.run_coacd(
        coacd.Mesh(mesh.vertices, mesh.faces.astype(np.int32)),
        threshold=threshold,
        max_convex_hull=max_convex_hull,
        seed=seed,
    )
    return [MeshData(np.asarray(v), np.asarray(f)) for v, f in result]


def _save_cache(path: str, result: Decomposition) -> None:
    """Write ``result`` as .npz atomically (temporary file + ``os.replace``)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    arrays: dict[str, Any] = {
        "meta": np.array([result.components, result.convex_components, len(result.parts)]),
    }
    for i, part in enumerate(result.parts):
        arrays[f"v{i}"], arrays[f"f{i}"] = part.vertices, part.faces
    tmp = f"{path}.{os.getpid()}.{uuid.uuid4().hex}.tmp"
    try:
        with open(tmp, "wb") as handle:
            np.savez(handle, **arrays)
        os.replace(tmp, path)
    except OSError:
        if os.path.exists(tmp):
            os.remove(tmp)


def _load_cache(path: str) -> Decomposition | None:
    """Read a cached decomposition, or None when absent or unreadable."""
    if not os.path.isfile(path):
        return None
    try:
        with np.load(path) as data:
            components, convex, count = (int(x) for x in data["meta"])
            parts = [MeshData(data[f"v{i}"], data[f"f{i}"]) for i in range(count)]
    except (OSError, KeyError, ValueError):
        return None
    return Decomposition(parts, components, convex, cached=True)


def decompose_file(
    path: str | os.PathLike[str],
    max_convex_hull_num: int = 8,
    cache_dir: str | os.PathLike[str] | None = None,
) -> DecompositionReport:
    """Decompose a mesh file, or every mesh a URDF references, and report what happened.

    Example:
        >>> print(decompose_file("drawer.urdf").format_table())  # doctest: +SKIP
    """
    from embodichain_core.sim.scene_build.mesh import load_mesh

    path = os.fspath(path)
    if path.lower().endswith(".urdf"):
        from embodichain_core.sim.scene_build.articulation_loader import urdf_mesh_files

        files = urdf_mesh_files(path)
    else:
        files = [path]
    report = DecompositionReport(path)
    for file in files:
        result = decompose(load_mesh(file), max_convex_hull_num, cache_dir=cache_dir)
        report.rows.append(
            MeshReport(
                os.path.basename(file),
                result.components,
                result.convex_components,
                len(result.parts),
                result.cached,
                result.seconds,
            )
        )
    return report
