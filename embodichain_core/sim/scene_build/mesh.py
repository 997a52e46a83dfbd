"""Triangle meshes: loading (trimesh), texture coordinates, components and convexity.

MuJoCo 4.0 decodes only STL, OBJ and MSH files, so meshes in other formats (PLY, GLB, glTF,
DAE) are loaded here and handed to ``mujoco.MjSpec`` as user vertices and faces with
:func:`add_mesh_to_spec`. Everything here is deterministic and cache-free; trimesh and MuJoCo are
imported inside the functions so that importing this module stays cheap.

Example:
    >>> mesh = load_mesh("table.ply", scale=(2, 1.6, 1), compute_uv=True)  # doctest: +SKIP
    >>> parts = split_components(mesh)  # doctest: +SKIP
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

MESH_SUFFIXES = (".ply", ".obj", ".stl", ".glb", ".gltf", ".dae", ".off")
MUJOCO_NATIVE_SUFFIXES = (".stl", ".obj", ".msh")


@dataclass
class MeshData:
    """A triangle mesh.

    Attributes:
        vertices: ``(V, 3)`` float64 positions.
        faces: ``(F, 3)`` int32 vertex indices, counter-clockwise seen from outside.
        texcoords: optional ``(V, 2)`` float64 texture coordinates.
        normals: optional ``(V, 3)`` float64 vertex normals.
    """

    vertices: np.ndarray
    faces: np.ndarray
    texcoords: np.ndarray | None = None
    normals: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)
        nv = len(self.vertices)
        if self.faces.size and (self.faces.min() < 0 or self.faces.max() >= nv):
            raise ValueError(f"face indices out of range for {nv} vertices")
        if self.texcoords is not None:
            self.texcoords = np.ascontiguousarray(self.texcoords, dtype=np.float64).reshape(nv, 2)
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=np.float64).reshape(nv, 3)

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3)`` array of the minimum and maximum corner."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def volume(self) -> float:
        """Signed enclosed volume (meaningful for closed, outward-oriented meshes)."""
        tri = self.vertices[self.faces]
        return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)

    def submesh(self, face_ids: np.ndarray) -> "MeshData":
        """The mesh made of ``faces[face_ids]`` with unused vertices dropped."""
        faces = self.faces[face_ids]
        used, inverse = np.unique(faces.ravel(), return_inverse=True)

        def pick(a: Optional[np.ndarray]) -> Optional[np.ndarray]:
            return None if a is None else a[used]

        return MeshData(self.vertices[used], inverse.reshape(-1, 3), pick(self.texcoords), pick(self.normals))


def load_mesh(
    path: str | os.PathLike[str],
    scale: Sequence[float] = (1.0, 1.0, 1.0),
    compute_uv: bool = False,
    project_direction: Sequence[float] = (1.0, 1.0, 1.0),
) -> MeshData:
    """Load a mesh file (.ply/.obj/.stl/.glb/.gltf; .dae needs pycollada) as one mesh.

    A file holding a scene (glTF) is flattened with its node transforms applied.

    Args:
        path: the mesh file.
        scale: per-axis scale applied to the vertices (a mirroring scale flips the winding).
        compute_uv: replace the texture coordinates by a box projection, see :func:`box_uv`.
        project_direction: per-axis weights of that projection.

    Example:
        >>> fork = load_mesh("fork.ply", scale=(0.75, 0.75, 1.0))  # doctest: +SKIP
    """
    import trimesh

    if not os.path.isfile(path):
        raise FileNotFoundError(f"mesh file {os.fspath(path)!r} does not exist")
    try:
        loaded = trimesh.load(os.fspath(path), process=True)
    except ImportError as exc:  # e.g. .dae needs pycollada
        raise ImportError(f"{path}: trimesh needs an optional package for this format: {exc}") from exc
    if isinstance(loaded, trimesh.Scene):
        if not loaded.geometry:
            raise ValueError(f"{path}: the file holds no geometry")
        loaded = loaded.to_mesh()
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"{path}: not a triangle mesh (got {type(loaded).__name__})")
    mesh = scale_mesh(from_trimesh(loaded), scale)
    return box_uv(mesh, project_direction) if compute_uv else mesh


def from_trimesh(tm: Any) -> MeshData:
    """Convert a ``trimesh.Trimesh`` (keeps UVs and vertex normals when the file had them)."""
    uv = getattr(tm.visual, "uv", None)
    if uv is not None and len(uv) != len(tm.vertices):
        uv = None
    normals = tm.vertex_normals if "vertex_normals" in tm._cache else None
    return MeshData(np.asarray(tm.vertices), np.asarray(tm.faces), uv, normals)


def scale_mesh(mesh: MeshData, scale: Sequence[float]) -> MeshData:
    """Scale vertices per axis; a negative determinant flips the face winding."""
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    if np.all(s == 1.0):
        return mesh
    faces = mesh.faces[:, ::-1] if np.prod(s) < 0 else mesh.faces
    normals = None
    if mesh.normals is not None:
        n = mesh.normals / np.where(s == 0, 1.0, s)
        normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    return MeshData(mesh.vertices * s, faces, mesh.texcoords, normals)


def face_normals(mesh: MeshData) -> np.ndarray:
    """``(F, 3)`` unit face normals (zero for degenerate faces)."""
    tri = mesh.vertices[mesh.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def box_uv(mesh: MeshData, project_direction: Sequence[float] = (1.0, 1.0, 1.0)) -> MeshData:
    """Texture coordinates by box (tri-planar) projection.

    Each face is projected onto the plane perpendicular to the axis ``a`` that maximises
    ``|normal[a]| * project_direction[a]``: ``(1, 1, 1)`` is the usual box mapping (the
    dominant normal axis per face), ``(0, 0, 1)`` a planar projection along Z for every face.
    Coordinates are divided by the largest bounding-box extent (no stretching) so they lie in
    ``[0, 1]``. Vertices shared by faces projected along different axes are duplicated.
    """
    weights = np.abs(np.asarray(project_direction, dtype=np.float64)).reshape(3)
    if not weights.any():
        raise ValueError("project_direction must have a non-zero component")
    axis = np.argmax(np.abs(face_normals(mesh)) * weights + weights * 1e-9, axis=1)
    key = mesh.faces.astype(np.int64).ravel() * 3 + np.repeat(axis, 3)
    unique, inverse = np.unique(key, return_inverse=True)
    src, src_axis = unique // 3, unique % 3
    lo, hi = mesh.bounds
    extent = max(float((hi - lo).max()), 1e-12)
    plane = np.array([[1, 2], [0, 2], [0, 1]])[src_axis]
    local = (mesh.vertices[src] - lo) / extent
    uv = np.take_along_axis(local, plane, axis=1)
    normals = None if mesh.normals is None else mesh.normals[src]
    return MeshData(mesh.vertices[src], inverse.reshape(-1, 3), uv, normals)


def merged_vertex_ids(mesh: MeshData, rel_tol: float = 1e-9) -> np.ndarray:
    """For each vertex, the index of the first vertex at the same position (within tolerance)."""
    if len(mesh.vertices) == 0:
        return np.zeros(0, dtype=np.int64)
    lo, hi = mesh.bounds
    eps = max(float((hi - lo).max()), 1e-12) * rel_tol
    keys = np.round((mesh.vertices - lo) / eps).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()]


def split_components(mesh: MeshData) -> list[MeshData]:
    """Split into connected components (faces sharing a vertex position are connected).

    Components come in the order of their first face, so the result is deterministic.
    """
    if len(mesh.faces) == 0:
        return []
    ids = merged_vertex_ids(mesh)[mesh.faces]
    edges = np.concatenate([ids[:, [0, 1]], ids[:, [1, 2]]])
    labels = _connected_labels(len(mesh.vertices), edges)[ids[:, 0]]
    _, first_face, face_label = np.unique(labels, return_index=True, return_inverse=True)
    order = np.argsort(first_face, kind="stable")
    return [mesh.submesh(np.flatnonzero(face_label == k)) for k in order]


def _connected_labels(n: int, edges: np.ndarray) -> np.ndarray:
    """Union-find by hooking and pointer jumping; every node gets its component's min node."""
    labels = np.arange(n)
    while True:
        a, b = labels[edges[:, 0]], labels[edges[:, 1]]
        hooked = labels.copy()
        np.minimum.at(hooked, np.maximum(a, b), np.minimum(a, b))
        while True:
            jumped = hooked[hooked]
            if np.array_equal(jumped, hooked):
                break
            hooked = jumped
        if np.array_equal(hooked, labels):
            return labels
        labels = hooked


def is_closed(mesh: MeshData) -> bool:
    """True when every edge (by vertex position) is shared by exactly two faces."""
    ids = merged_vertex_ids(mesh)[mesh.faces]
    edges = np.sort(np.concatenate([ids[:, [0, 1]], ids[:, [1, 2]], ids[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(len(counts)) and bool(np.all(counts == 2))


def convex_hull(mesh: MeshData) -> MeshData:
    """The convex hull, computed by MuJoCo's own qhull (the hull MuJoCo collides with).

    Raises:
        ValueError: the points are degenerate (flat or fewer than four).
    """
    import mujoco

    spec = mujoco.MjSpec()
    spec.add_mesh(
        name="hull",
        uservert=mesh.vertices.ravel().tolist(),
        userface=mesh.faces.ravel().tolist(),
        maxhullvert=-1,
        inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
    )
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="hull")
    try:
        model = spec.compile()
    except ValueError as exc:
        raise ValueError(f"cannot build a convex hull: {exc}") from exc
    if model.mesh_graphadr[0] < 0:
        raise ValueError("cannot build a convex hull: degenerate points")
    graph = model.mesh_graph[model.mesh_graphadr[0] :]
    nv, nf = int(graph[0]), int(graph[1])
    tri = graph[2 + 3 * nv + 3 * nf : 2 + 3 * nv + 6 * nf].reshape(-1, 3)
    start, count = model.mesh_vertadr[0], model.mesh_vertnum[0]
    local = model.mesh_vert[start : start + count].astype(np.float64)
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.mesh_quat[0].astype(np.float64))
    world = local @ rot.reshape(3, 3).T + model.mesh_pos[0]
    used, inverse = np.unique(tri.ravel(), return_inverse=True)
    return MeshData(world[used], inverse.reshape(-1, 3))


def is_convex(mesh: MeshData, tol: float = 0.02) -> bool:
    """Whether the mesh is convex up to ``tol``.

    A closed mesh is convex when ``1 - volume / hull_volume <= tol``. An open mesh is convex
    when every vertex lies within ``tol * hull extent`` of the hull surface. Flat meshes count
    as convex (their hull is the mesh itself).
    """
    try:
        hull = convex_hull(mesh)
    except ValueError:
        return True
    hull_volume = abs(hull.volume)
    if hull_volume <= 1e-15:
        return True
    if is_closed(mesh):
        return bool(1.0 - abs(mesh.volume) / hull_volume <= tol)
    return bool(_max_depth_inside(mesh.vertices, hull) <= tol * float(np.ptp(hull.bounds, axis=0).max()))


def _max_depth_inside(points: np.ndarray, hull: MeshData) -> float:
    """Largest distance from a point to the surface of a convex ``hull`` (points inside it)."""
    normals = face_normals(hull)
    offsets = np.einsum("ij,ij->i", normals, hull.vertices[hull.faces[:, 0]])
    depth = 0.0
    for chunk in np.array_split(points, max(1, len(points) // 4096)):
        dist = offsets[None, :] - chunk @ normals.T
        depth = max(depth, float(np.maximum(dist.min(axis=1), 0.0).max()))
    return depth


def mesh_hash(mesh: MeshData, **params: Any) -> str:
    """SHA-256 of the vertex and face bytes plus the JSON of ``params`` (sorted keys)."""
    digest = hashlib.sha256()
    digest.update(np.ascontiguousarray(mesh.vertices, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype="<i4").tobytes())
    digest.update(json.dumps(params, sort_keys=True, default=str).encode())
    return digest.hexdigest()


def add_mesh_to_spec(spec: Any, name: str, mesh: MeshData, **attrs: Any) -> Any:
    """Add ``mesh`` to a ``mujoco.MjSpec`` as user vertices/faces (and texcoords).

    Extra keyword arguments are set on the ``MjsMesh`` (``scale=[...]``, ``maxhullvert=...``).

    Example:
        >>> spec = mujoco.MjSpec()  # doctest: +SKIP
        >>> add_mesh_to_spec(spec, "fork", load_mesh("fork.ply"))  # doctest: +SKIP
    """
    element = spec.add_mesh(name=name)
    set_user_mesh(element, mesh)
    for key, value in attrs.items():
        setattr(element, key, value)
    return element


def set_user_mesh(element: Any, mesh: MeshData) -> None:
    """Fill a ``mujoco.MjsMesh`` with ``mesh`` and clear its ``file``."""
    element.file = ""
    element.uservert = mesh.vertices.ravel().tolist()
    element.userface = mesh.faces.ravel().tolist()
    if mesh.texcoords is not None:
        element.usertexcoord = mesh.texcoords.ravel().tolist()
