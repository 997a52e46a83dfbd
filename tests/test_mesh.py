"""Mesh loading, UVs, components, convexity, hashing and coacd collision parts with its cache."""

from __future__ import annotations

import subprocess
import sys

import mujoco
import numpy as np
import pytest
import trimesh

from embodichain_core.sim.scene_build import convex
from embodichain_core.sim.scene_build.convex import collision_parts, decompose
from embodichain_core.sim.scene_build.mesh import (
    MeshData,
    add_mesh_to_spec,
    box_uv,
    convex_hull,
    is_closed,
    is_convex,
    load_mesh,
    mesh_hash,
    scale_mesh,
    split_components,
)


def grid_prism(mask: list[list[int]], cell: float = 0.05, height: float = 0.05) -> MeshData:
    """A closed, outward-oriented prism over the filled cells of a 2D grid (one component)."""
    index: dict[tuple[int, int, int], int] = {}
    faces: list[tuple[int, int, int]] = []

    def vid(x: int, y: int, z: int) -> int:
        return index.setdefault((x, y, z), len(index))

    def quad(a, b, c, d) -> None:
        faces.extend([(vid(*a), vid(*b), vid(*c)), (vid(*a), vid(*c), vid(*d))])

    rows, cols = len(mask), len(mask[0])
    filled = lambda r, c: 0 <= r < rows and 0 <= c < cols and mask[r][c]  # noqa: E731
    for r in range(rows):
        for c in range(cols):
            if not mask[r][c]:
                continue
            quad((c, r, 1), (c + 1, r, 1), (c + 1, r + 1, 1), (c, r + 1, 1))
            quad((c, r, 0), (c, r + 1, 0), (c + 1, r + 1, 0), (c + 1, r, 0))
            if not filled(r - 1, c):
                quad((c, r, 0), (c + 1, r, 0), (c + 1, r, 1), (c, r, 1))
            if not filled(r + 1, c):
                quad((c, r + 1, 0), (c, r + 1, 1), (c + 1, r + 1, 1), (c + 1, r + 1, 0))
            if not filled(r, c - 1):
                quad((c, r, 0), (c, r, 1), (c, r + 1, 1), (c, r + 1, 0))
            if not filled(r, c + 1):
                quad((c + 1, r, 0), (c + 1, r + 1, 0), (c + 1, r + 1, 1), (c + 1, r, 1))
    verts = np.array(sorted(index, key=index.get), dtype=float) * [cell, cell, height]
    return MeshData(verts, np.array(faces))


L_SHAPE = [[1, 0], [1, 1]]
U_SHAPE = [[1, 0, 1], [1, 1, 1]]


def two_boxes() -> MeshData:
    a = trimesh.creation.box((0.1, 0.1, 0.1))
    b = trimesh.creation.box((0.1, 0.1, 0.1))
    b.apply_translation((0.3, 0.0, 0.0))
    merged = trimesh.util.concatenate([a, b])
    return MeshData(merged.vertices, merged.faces)


@pytest.fixture
def coacd_calls(monkeypatch):
    """Count calls of the coacd seam while still running coacd."""
    calls: list[int] = []
    real = convex._run_coacd

    def counting(mesh, max_convex_hull, threshold, seed):
        calls.append(max_convex_hull)
        return real(mesh, max_convex_hull, threshold, seed)

    monkeypatch.setattr(convex, "_run_coacd", counting)
    return calls


# --- loading -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".stl", ".glb"])
def test_load_round_trip_with_scale(tmp_path, suffix):
    box = trimesh.creation.box((0.2, 0.1, 0.05))
    path = tmp_path / f"box{suffix}"
    box.export(path)
    mesh = load_mesh(path, scale=(2.0, 1.0, 0.5))
    assert mesh.vertices.dtype == np.float64
    assert mesh.faces.dtype == np.int32
    assert mesh.vertices.shape[1] == 3
    assert len(mesh.faces) == 12
    np.testing.assert_allclose(mesh.bounds, [[-0.2, -0.05, -0.0125], [0.2, 0.05, 0.0125]], atol=1e-6)
    assert mesh.volume == pytest.approx(0.4 * 0.1 * 0.025, rel=1e-5)


def test_scene_is_flattened_with_transforms(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box((0.1, 0.1, 0.1)), node_name="a")
    moved = np.eye(4)
    moved[:3, 3] = (1.0, 0.0, 0.0)
    scene.add_geometry(trimesh.creation.box((0.1, 0.1, 0.1)), node_name="b", transform=moved)
    scene.export(tmp_path / "two.glb")
    mesh = load_mesh(tmp_path / "two.glb")
    assert len(split_components(mesh)) == 2
    assert mesh.bounds[1, 0] == pytest.approx(1.05)


def test_mirroring_scale_keeps_outward_faces():
    mesh = MeshData(trimesh.creation.box().vertices, trimesh.creation.box().faces)
    assert scale_mesh(mesh, (-1.0, 1.0, 1.0)).volume == pytest.approx(1.0)


def test_compute_uv_box_projection(tmp_path):
    trimesh.creation.icosphere(2).export(tmp_path / "sphere.ply")
    mesh = load_mesh(tmp_path / "sphere.ply", compute_uv=True)
    assert mesh.texcoords is not None
    assert mesh.texcoords.shape == (len(mesh.vertices), 2)
    assert mesh.texcoords.min() >= -1e-9
    assert mesh.texcoords.max() <= 1 + 1e-9
    assert len(split_components(mesh)) == 1
    assert is_closed(mesh)


def test_planar_projection_needs_no_duplicates():
    box = trimesh.creation.box((2.0, 1.0, 1.0))
    mesh = box_uv(MeshData(box.vertices, box.faces), project_direction=(0, 0, 1))
    assert len(mesh.vertices) == 8
    np.testing.assert_allclose(mesh.texcoords[:, 0], (mesh.vertices[:, 0] + 1.0) / 2.0)
    np.testing.assert_allclose(mesh.texcoords[:, 1], (mesh.vertices[:, 1] + 0.5) / 2.0)


def test_add_mesh_to_spec_compiles_with_texcoords():
    box = trimesh.creation.box((0.1, 0.1, 0.1))
    spec = mujoco.MjSpec()
    add_mesh_to_spec(spec, "box", box_uv(MeshData(box.vertices, box.faces)), scale=[2.0, 2.0, 2.0])
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="box")
    model = spec.compile()
    assert model.mesh_texcoordnum[0] > 0
    assert model.geom_rbound[0] == pytest.approx(np.sqrt(3) * 0.1, rel=1e-5)


# --- components, convexity, hashing --------------------------------------------------------


def test_split_components():
    parts = split_components(two_boxes())
    assert len(parts) == 2
    assert [p.bounds[0, 0] for p in parts] == pytest.approx([-0.05, 0.25])
    assert all(len(p.faces) == 12 and len(p.vertices) == 8 for p in parts)
    assert len(split_components(grid_prism(U_SHAPE))) == 1


def test_grid_prism_is_closed_and_outward():
    mesh = grid_prism(L_SHAPE)
    assert is_closed(mesh)
    assert mesh.volume == pytest.approx(3 * 0.05**3)


def test_convexity():
    assert is_convex(MeshData(trimesh.creation.box().vertices, trimesh.creation.box().faces))
    sphere = trimesh.creation.icosphere(2)
    assert is_convex(MeshData(sphere.vertices, sphere.faces))
    assert not is_convex(grid_prism(L_SHAPE))
    assert not is_convex(two_boxes())
    assert is_convex(grid_prism([[1, 1], [1, 1]]))


def test_convex_hull_of_l_shape():
    hull = convex_hull(grid_prism(L_SHAPE))
    assert hull.volume == pytest.approx(3.5 * 0.05**3, rel=1e-5)
    assert is_closed(hull)


def test_mesh_hash_is_content_and_param_sensitive():
    mesh = grid_prism(L_SHAPE)
    assert mesh_hash(mesh, n=2) == mesh_hash(grid_prism(L_SHAPE), n=2)
    assert mesh_hash(mesh, n=2) != mesh_hash(mesh, n=3)
    moved = MeshData(mesh.vertices + 1e-6, mesh.faces)
    assert mesh_hash(moved, n=2) != mesh_hash(mesh, n=2)


# --- collision parts (coacd + cache) -------------------------------------------------------


def test_convex_components_skip_coacd(tmp_path, monkeypatch):
    monkeypatch.setattr(convex, "_run_coacd", lambda *a: pytest.fail("coacd must not run"))
    parts = collision_parts(two_boxes(), max_convex_hull_num=8, cache_dir=tmp_path)
    assert len(parts) == 2
    assert not any(tmp_path.rglob("*.npz"))


def test_single_hull_uses_convex_hull_without_coacd(tmp_path, monkeypatch):
    monkeypatch.setattr(convex, "_run_coacd", lambda *a: pytest.fail("coacd must not run"))
    (part,) = collision_parts(grid_prism(L_SHAPE), max_convex_hull_num=1, cache_dir=tmp_path)
    assert part.volume == pytest.approx(3.5 * 0.05**3, rel=1e-5)


def test_coacd_runs_once_then_cache_hits(tmp_path, coacd_calls):
    mesh = grid_prism(L_SHAPE)
    first = decompose(mesh, max_convex_hull_num=4, cache_dir=tmp_path)
    assert coacd_calls == [4]
    assert not first.cached
    assert 1 <= len(first.parts) <= 4
    assert all(is_convex(p) for p in first.parts)
    files = list(tmp_path.rglob("*"))
    assert [f.suffix for f in files if f.is_file()] == [".npz"]  # no temporary file left over
    second = decompose(grid_prism(L_SHAPE), max_convex_hull_num=4, cache_dir=tmp_path)
    assert coacd_calls == [4]
    assert second.cached
    assert len(second.parts) == len(first.parts)
    for a, b in zip(first.parts, second.parts):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
    decompose(mesh, max_convex_hull_num=3, cache_dir=tmp_path)  # other params: other key
    assert coacd_calls == [4, 3]


def test_cache_dir_from_environment(tmp_path, monkeypatch, coacd_calls):
    monkeypatch.setenv("EMBODICHAIN_CACHE_DIR", str(tmp_path / "cache"))
    assert convex.cache_root() == str(tmp_path / "cache" / "coacd")
    collision_parts(grid_prism(L_SHAPE), max_convex_hull_num=2)
    assert list((tmp_path / "cache" / "coacd").rglob("*.npz"))


def test_max_convex_hull_num_is_honoured(tmp_path):
    mesh = grid_prism(U_SHAPE)
    for n in (2, 3):
        parts = collision_parts(mesh, max_convex_hull_num=n, cache_dir=tmp_path)
        assert 1 <= len(parts) <= n


def test_corrupt_cache_is_recomputed(tmp_path, coacd_calls):
    mesh = grid_prism(L_SHAPE)
    decompose(mesh, max_convex_hull_num=2, cache_dir=tmp_path)
    (cached,) = list(tmp_path.rglob("*.npz"))
    cached.write_bytes(b"garbage")
    again = decompose(mesh, max_convex_hull_num=2, cache_dir=tmp_path)
    assert not again.cached
    assert len(coacd_calls) == 2


def test_unknown_method_is_an_error():
    with pytest.raises(ValueError, match="Did you mean 'coacd'"):
        collision_parts(two_boxes(), method="coacdd")
    with pytest.raises(ValueError):
        collision_parts(two_boxes(), max_convex_hull_num=0)


def test_importing_mesh_modules_does_not_import_trimesh_or_coacd():
    code = (
        "import sys, embodichain_core; before = set(sys.modules); "
        "import embodichain_core.sim.scene_build.mesh, embodichain_core.sim.scene_build.convex; "
        "print(sorted(m for m in ('trimesh', 'coacd', 'mujoco') if m in set(sys.modules) - before))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
