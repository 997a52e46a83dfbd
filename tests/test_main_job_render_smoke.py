"""Smoke test of ``benchmarks/main_job_render.py``: one round per ``render_threads`` contender
and the profiled round run, and the JSON holds what docs/sensors.md reads. No timing is
asserted (the box is shared and noisy). Slow: it runs the main job three times (about a minute)."""

from __future__ import annotations

import pytest
from bench_testlib import run_benchmark


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_one_round_per_contender_writes_json(tmp_path):
    args = ("--rounds", "1", "--render-threads", "1", "2")
    _, data = run_benchmark("main_job_render.py", *args, out=tmp_path / "main_job_render.json", timeout=580)
    assert set(data["rounds"]) == {"1", "2"}
    for threads, (rnd,) in data["rounds"].items():
        # every env step renders both eyes of both envs (resets add frames)
        assert rnd["frames"] >= 2 * rnd["env_steps"] > 0, threads
        assert rnd["bare_render_s"] > 0
        assert rnd["ratio"] > 0
        assert data["summary"][threads]["env_steps_per_s"] == pytest.approx(rnd["env_steps_per_s"])
    assert data["summary"]["1"]["speedup_over_first"] == pytest.approx(1.0)
    parts = data["breakdown_ms_per_env_step"]
    assert parts["rasterization"] > parts["read_back"] > 0
    assert parts["segmentation_pass"] == 0.0  # the main job renders colour only
    outside = sum(parts[k] for k in ("camera_total", "physics", "scripted_planner", "recorder", "rest"))
    assert outside == pytest.approx(parts["total"], rel=0.02)
