"""Smoke test of the backend-warp table of ``benchmarks/render_throughput.py``: 2 worlds of
32x24, both renderers, the documented JSON rows. No timing is asserted."""

from __future__ import annotations

from bench_testlib import run_benchmark

ROW_KEYS = {"renderer", "device", "worlds", "resolution", "frames_per_s", "env_steps_per_s", "first_update_s"}


def test_warp_rows_of_both_renderers(tmp_path) -> None:
    args = ("--skip-opengl-table", "--warp-worlds", "2", "--warp-sizes", "32x24", "--min-seconds", "0")
    _, payload = run_benchmark("render_throughput.py", *args, out=tmp_path / "render.json", timeout=300)
    assert payload["rows"] == []
    rows = payload["warp_rows"]
    assert [(r["renderer"], r["worlds"], r["resolution"]) for r in rows] == [
        ("warp", 2, "32x24"),
        ("opengl", 2, "32x24"),
    ]
    for row in rows:
        assert set(row) == ROW_KEYS
        assert row["frames_per_s"] > 0
        assert row["env_steps_per_s"] > 0
