"""``embodichain decompose``: mesh files, URDFs, the cache column, errors."""

from __future__ import annotations

import numpy as np
import trimesh

from embodichain_core.cli.decompose import main
from embodichain_core.sim.scene_build.convex import decompose_file


def l_shape_mesh() -> trimesh.Trimesh:
    """A closed, non-convex L-shaped prism (one connected component)."""
    outline = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], dtype=float) * 0.05
    n = len(outline)
    verts = np.vstack([np.c_[outline, np.zeros(n)], np.c_[outline, np.full(n, 0.05)]])
    faces = []
    for a, b, c in [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]:  # fan from the reflex corner
        faces += [(a, c, b), (a + n, b + n, c + n)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    mesh = trimesh.Trimesh(verts, np.array(faces), process=False)
    assert mesh.volume > 0
    return mesh


def table_rows(output: str) -> list[list[str]]:
    lines = output.strip().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("mesh"))
    return [line.split() for line in lines[start + 2 :]]


def test_mesh_file_first_run_then_cached(tmp_path, capsys):
    l_shape_mesh().export(tmp_path / "l_shape.ply")
    args = [str(tmp_path / "l_shape.ply"), "--max-hulls", "3", "--cache-dir", str(tmp_path / "cache")]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "components" in out
    assert "cached" in out
    (row,) = table_rows(out)
    assert row[:3] == ["l_shape.ply", "1", "0"]
    assert 1 <= int(row[3]) <= 3
    assert row[4] == "no"
    assert main(args) == 0
    (row,) = table_rows(capsys.readouterr().out)
    assert row[4] == "yes"


def test_urdf_reports_every_mesh(tmp_path, capsys):
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box((0.1, 0.1, 0.1)).export(tmp_path / "meshes" / "box.stl")
    l_shape_mesh().export(tmp_path / "meshes" / "l.obj")
    urdf = tmp_path / "thing.urdf"
    urdf.write_text(
        '<robot name="thing"><link name="a">'
        '<visual><geometry><mesh filename="meshes/box.stl"/></geometry></visual>'
        '<collision><geometry><mesh filename="meshes/box.stl"/></geometry></collision>'
        '<collision><geometry><mesh filename="package://thing/meshes/l.obj"/></geometry></collision>'
        "</link></robot>"
    )
    assert main([str(urdf), "--max-hulls", "1", "--cache-dir", str(tmp_path / "c")]) == 0
    rows = table_rows(capsys.readouterr().out)
    assert [r[0] for r in rows] == ["box.stl", "l.obj"]
    assert rows[0][1:4] == ["1", "1", "1"]
    assert rows[1][1:4] == ["1", "0", "1"]


def test_report_object(tmp_path):
    l_shape_mesh().export(tmp_path / "l.stl")
    report = decompose_file(tmp_path / "l.stl", max_convex_hull_num=2, cache_dir=tmp_path / "c")
    (row,) = report.rows
    assert row.components == 1
    assert row.convex_components == 0
    assert 1 <= row.hulls <= 2
    assert not row.cached
    assert row.seconds >= 0
    assert report.format_table().splitlines()[0].split() == [
        "mesh",
        "components",
        "convex",
        "hulls",
        "cached",
        "time",
        "[s]",
    ]


def test_missing_file_is_an_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("EMBODICHAIN_DATA_ROOT", str(tmp_path))
    assert main([str(tmp_path / "nope.ply")]) == 1
    assert "error" in capsys.readouterr().err
