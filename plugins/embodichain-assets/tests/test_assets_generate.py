"""The generator is deterministic, and the shipped files are exactly what it produces."""

from __future__ import annotations

import numpy as np
import pytest

from embodichain_assets import DATA_ROOT, generate, textures
from embodichain_assets.pngread import read_png
from embodichain_assets.writers import obj_bytes, ply_bytes, png_bytes
from embodichain_core.sim.scene_build.mesh import load_mesh


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """The pack generated into a fresh folder: (folder, written paths)."""
    folder = tmp_path_factory.mktemp("pack")
    return folder, generate.generate(folder)


def test_regenerating_gives_byte_identical_files(generated):
    folder, paths = generated
    again = generate.pack_files()  # a second, independent run of every producer
    assert sorted(again) == sorted(p.relative_to(folder).as_posix() for p in paths)
    for path in paths:
        assert again[path.relative_to(folder).as_posix()]() == path.read_bytes(), path.relative_to(folder)


def test_shipped_data_matches_the_generator(generated):
    first, paths = generated
    shipped = sorted(p.relative_to(DATA_ROOT).as_posix() for p in DATA_ROOT.rglob("*") if p.is_file())
    assert shipped == sorted(p.relative_to(first).as_posix() for p in paths)  # no missing, no stale files
    for path in paths:
        name = path.relative_to(first).as_posix()
        new, old = path.read_bytes(), (DATA_ROOT / name).read_bytes()
        if name.endswith(".png"):  # another zlib may deflate differently: compare pixels
            np.testing.assert_array_equal(read_png(new), read_png(old), err_msg=name)
        elif name.endswith((".ply", ".obj")):  # another libm may differ in the last bit: compare arrays
            a, b = load_mesh(path), load_mesh(DATA_ROOT / name)
            np.testing.assert_array_equal(a.faces, b.faces, err_msg=name)
            np.testing.assert_allclose(a.vertices, b.vertices, atol=1e-6, err_msg=name)
        else:
            assert new == old, name


def test_check_command_names_the_files_that_differ(generated, capsys):
    folder, _ = generated
    victim = folder / "SlidingBoxDrawer" / "SlidingBoxDrawer.urdf"
    original = victim.read_bytes()
    try:
        victim.write_bytes(original.replace(b"0.2", b"0.3"))
        assert generate.main(["--check", "--out", str(folder)]) == 1
    finally:
        victim.write_bytes(original)
    lines = capsys.readouterr().out.splitlines()
    differs = [line for line in lines if line.startswith("differs:")]
    assert differs == ["differs: SlidingBoxDrawer/SlidingBoxDrawer.urdf"]


def test_pack_stays_small():
    size = sum(p.stat().st_size for p in DATA_ROOT.rglob("*") if p.is_file())
    assert size < 3_000_000, size


def test_png_writer_round_trips_every_filter_type():
    rng = np.random.default_rng(0)
    smooth = np.cumsum(rng.integers(0, 3, (40, 37, 3)), axis=1).astype(np.uint8)  # Sub/Paeth rows
    noisy = rng.integers(0, 256, (23, 31, 3), dtype=np.uint8)  # None rows
    stripes = np.repeat(rng.integers(0, 256, (1, 50, 3), dtype=np.uint8), 20, axis=0)  # Up rows
    for image in (smooth, noisy, stripes, textures.texture(7)):
        np.testing.assert_array_equal(read_png(png_bytes(image)), image)


def test_mesh_writers_round_trip(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) * 0.1
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    for suffix, data in ((".ply", ply_bytes(vertices, faces)), (".obj", obj_bytes(vertices, faces))):
        path = tmp_path / f"tetra{suffix}"
        path.write_bytes(data)
        mesh = load_mesh(path)
        assert len(mesh.faces) == 4
        assert mesh.volume == pytest.approx(0.1**3 / 6, rel=1e-5)
