"""Smoke test of ``benchmarks/record_encoder_processes.py --quick``: a recording with the
videos encoded by the writer process and one with 2 encoder processes, each saving its
episodes, and the documented JSON. No timing is asserted (the box is shared and noisy)."""

from __future__ import annotations

import pytest
from bench_testlib import run_benchmark

pytest.importorskip("embodichain_sensors")
pytest.importorskip("embodichain_lerobot")

ROW_KEYS = {"encoder_processes", "env_steps_per_s", "end_to_end_steps_per_s", "cpu_ms_per_env_step", "runs"}


@pytest.mark.slow  # two small recordings, each in its own process (~2-3 min on 2 loaded cores)
def test_quick_run_records_with_one_and_two_encoder_processes(tmp_path) -> None:
    _, payload = run_benchmark("record_encoder_processes.py", "--quick", out=tmp_path / "enc.json", timeout=900)
    rows = payload["rows"]
    assert [row["encoder_processes"] for row in rows] == [1, 2]
    for row in rows:
        assert set(row) == ROW_KEYS
        (run,) = row["runs"]
        assert run["episodes_saved"] >= 2 * 2, "2 envs: the warm-up episode and one more each"
        assert run["cpu_ms_per_env_step"] > 0
        assert run["end_to_end_steps_per_s"] <= run["env_steps_per_s"]
    assert payload["args"]["num_envs"] == 2
