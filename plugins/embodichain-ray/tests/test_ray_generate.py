"""``embodichain generate`` on a local Ray: merge, determinism across workers, a killed
worker, an invalid config."""

from __future__ import annotations

import json
import os
import re
import signal
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from embodichain_ray import cli
from embodichain_ray.spec import episode_seed
from ray_helpers import episode_arrays, load, sidecar

from embodichain_core.cli import run_env


def _generate(config: str, out: Path, workers: int, *extra: str, **kw: Any) -> int:
    argv = [
        "--gym_config",
        config,
        "--episodes",
        "6",
        "--workers",
        str(workers),
        "--seed",
        "3",
        "--output",
        str(out),
        "--quiet",
        *extra,
    ]
    return cli.main(argv, **kw)


def test_the_command_is_registered() -> None:
    from embodichain_core.plugins import command_registry, load_plugins

    load_plugins()
    entry = command_registry().find("generate")
    assert entry is not None
    assert entry.target == "embodichain_ray.cli:main"


def test_two_workers_merge_six_loadable_episodes_in_episode_order(
    tmp_path: Path, tiny_config: Any, capsys: Any
) -> None:
    out = tmp_path / "merged"
    assert _generate(tiny_config(), out, 2) == 0
    summary = capsys.readouterr().out
    assert "6/6 merged" in summary
    assert str(out) in summary
    assert "worker  episodes  failures  env-steps/s  restarts" in summary
    ds = load(out)
    assert ds.num_episodes == 6
    assert ds.num_frames == 60
    assert tuple(ds[59]["observation.images.eye_in_head"].shape) == (3, 64, 64)
    lines = sidecar(out)
    assert [line["generate"]["episode"] for line in lines] == list(range(6))
    assert [line["episode_seed"] for line in lines] == [episode_seed(3, k) for k in range(6)]
    assert not out.with_name(out.name + ".shards").exists()  # merged: the shards are removed


def test_an_invalid_config_fails_like_run_env_before_any_worker_starts(
    tmp_path: Path, tiny_config: Any, capsys: Any
) -> None:
    import ray

    data = json.loads(Path(tiny_config()).read_text())
    data["env"]["events"]["fork_mass"]["params"]["mass_range"] = [0.1, -0.2]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    assert run_env.main(["--gym_config", str(bad), "--headless"]) == 2
    expected = capsys.readouterr().err.strip().split(": config error", 1)[1]
    out = tmp_path / "never"
    assert _generate(str(bad), out, 2) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("embodichain generate: config error")
    assert err.endswith(expected)
    assert "fork_mass" in err
    assert not ray.is_initialized()
    assert not out.exists()
    assert not out.with_name("never.shards").exists()


def test_counts_and_an_existing_output_are_config_errors(tmp_path: Path, tiny_config: Any, capsys: Any) -> None:
    assert _generate(tiny_config(), tmp_path / "x", 0) == 2
    assert "--workers: must be >= 1" in capsys.readouterr().err
    assert _generate(tiny_config(), tmp_path, 1) == 2
    assert "exists" in capsys.readouterr().err


@pytest.mark.slow
def test_one_and_two_workers_record_identical_episodes(tmp_path: Path, tiny_config: Any) -> None:
    config = tiny_config()
    assert _generate(config, tmp_path / "w1", 1) == 0
    assert _generate(config, tmp_path / "w2", 2) == 0
    assert _generate(config, tmp_path / "w1k4", 1, "--num_envs", "4") == 0  # 6 = 4 + 2 and 2 idle slots
    runs = [episode_arrays(tmp_path / name) for name in ("w1", "w2", "w1k4")]
    assert [len(r) for r in runs] == [6, 6, 6]
    for other in runs[1:]:
        for a, b in zip(runs[0], other):
            for key in ("observation.state", "action"):
                np.testing.assert_array_equal(a[key], b[key])
    seeds = [[x["episode_seed"] for x in sidecar(tmp_path / name)] for name in ("w1", "w2", "w1k4")]
    assert seeds[0] == seeds[1] == seeds[2]


def _kill_after_first_episode(shards: Path, killed: list) -> Any:
    """An ``on_start`` hook: SIGKILL worker 0 once its shard has published an episode."""
    import ray

    def watch(pid: int) -> None:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            for info in (shards / "worker-000").glob("*/meta/info.json"):
                if json.loads(info.read_text()).get("total_episodes", 0) >= 1:
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pid)
                    return
            time.sleep(0.05)

    def on_start(actors: list) -> None:
        pid = ray.get(actors[0].pid.remote())
        threading.Thread(target=watch, args=(pid,), daemon=True).start()

    return on_start


@pytest.mark.slow
def test_a_worker_killed_mid_run_still_yields_six_loadable_episodes(
    tmp_path: Path, tiny_config: Any, capsys: Any
) -> None:
    out, killed = tmp_path / "merged", []
    shards = out.with_name("merged.shards")
    hook = _kill_after_first_episode(shards, killed)
    config = tiny_config(max_episode_steps=40)  # ~1 s episodes: the kill lands mid-run
    assert _generate(config, out, 2, "--keep-shards", on_start=hook) == 0
    captured = capsys.readouterr()
    summary = captured.out
    assert killed, "worker 0 was never killed"
    # said in words: which worker, which episodes, what happens now; not Ray's raw notes
    died = r"worker 0 died while running episode\(s\) \d+ \(its process died( \(pid \d+\))?: killed, or it crashed\); "
    assert re.search(died + r"Ray restarts it \(restart 1 of 3\) and they run again", captured.err), captured.err
    assert "A worker died or was killed" not in captured.out + captured.err
    assert "RpcError" not in captured.out + captured.err
    first = min((shards / "worker-000").glob("*/meta/info.json")).parent.parent
    assert (first / ".embodichain_staging").exists()  # the killed incarnation's shard, never finalized
    rows = [line.split() for line in summary.splitlines() if line.strip().startswith("0 ")]
    assert rows, summary
    assert rows[0][-1] == "1", summary  # worker 0: one restart
    ds = load(out)
    assert ds.num_episodes == 6
    assert ds.num_frames == 240
    assert [line["generate"]["episode"] for line in sidecar(out)] == list(range(6))
