"""Kill tests of ``embodichain generate`` with the ``AsyncLeRobotRecorder`` (a writer process
per worker): a worker killed mid-run or while closing, a Ctrl-C, a ``SIGTERM`` and a ``SIGKILL``
of the driver. Each checks that every episode counted as saved loads with ``LeRobotDataset``
from the merged dataset, and that the summary's counts (merged, the worker table) are what the
merged dataset holds; the driver's signals also that no process of its Ray outlives it.

The timing is set by the writer processes' test gate (``EMBODICHAIN_WRITER_TEST_GATE``: how
many episodes each may write; a held episode is announced in ``<gate>.held``), never by sleeps.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

import pytest
from embodichain_ray import cli, run
from embodichain_ray.spec import episode_seed
from ray_helpers import load, ray_processes, sidecar, still_running

from embodichain_lerobot.writer_child import TEST_GATE_ENV

pytestmark = pytest.mark.slow  # each test runs a two-worker generate (~30-60 s on 2 cores)


def _async_config(tiny_config: Any, **overrides: Any) -> str:
    path = Path(tiny_config(**overrides))
    data = json.loads(path.read_text())
    data["env"]["dataset"]["lerobot"]["func"] = "AsyncLeRobotRecorder"
    path.write_text(json.dumps(data))
    return str(path)


def _generate(config: str, out: Path, hook: Callable[[list], None] | None = None) -> int:
    argv = ["--gym_config", config, "--episodes", "6", "--workers", "2", "--seed", "3", "--output", str(out)]
    return cli.main([*argv, "--quiet", "--keep-shards"], on_start=hook)


def _summary_counts(summary: str) -> tuple[int, list[int]]:
    merged = int(re.search(r"episodes\s+(\d+)/6 merged", summary).group(1))
    rows = [line.split() for line in summary.splitlines() if re.match(r"\s+[01]\s+\d+\s+\d+", line)]
    return merged, [int(r[1]) for r in rows]


def _check(out: Path, summary: str) -> int:
    """The summary's counts match the merged dataset, which loads; the number of episodes."""
    merged, table = _summary_counts(summary)
    ds = load(out)
    assert ds.num_episodes == merged == sum(table), summary
    assert len(ds) == sum(int(n) for n in ds.meta.episodes["length"])
    seeds = [line["episode_seed"] for line in sidecar(out)]
    episodes = [line["generate"]["episode"] for line in sidecar(out)]
    assert seeds == [episode_seed(3, k, line["generate"]["attempt"]) for k, line in zip(episodes, sidecar(out))]
    return merged


class Gate:
    """The writer processes' test gate, set through the environment the workers inherit."""

    def __init__(self, tmp_path: Path, monkeypatch: Any, allowed: int):
        self.path = tmp_path / "gate"
        self.open(allowed)
        monkeypatch.setenv(TEST_GATE_ENV, str(self.path))

    def open(self, allowed: int) -> None:
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(str(allowed))
        os.replace(tmp, self.path)

    def held(self, worker: str, index: int) -> bool:
        """Whether a writer of ``worker`` (``worker-000``) holds its episode ``index``."""
        path = Path(f"{self.path}.held")
        lines = path.read_text().splitlines() if path.exists() else []
        return any(worker in line and int(line.split()[-1]) >= index for line in lines)

    def wait_held(self, workers: list[str], index: int, timeout: float = 240) -> None:
        deadline = time.monotonic() + timeout
        while not all(self.held(w, index) for w in workers):
            assert time.monotonic() < deadline, "the writers never held the episode"
            time.sleep(0.05)


def _in_thread(target: Callable[[], None]) -> Callable[[list], None]:
    def on_start(actors: list) -> None:
        threading.Thread(target=target, daemon=True).start()

    return on_start


def test_a_worker_killed_with_an_unwritten_episode_has_it_run_again(
    tmp_path: Path, tiny_config: Any, monkeypatch: Any, capsys: Any
) -> None:
    import ray

    gate, out = Gate(tmp_path, monkeypatch, allowed=1), tmp_path / "merged"
    pids: list = []

    def kill() -> None:  # worker 0 finished its 2nd episode; its writer holds it (not durable)
        gate.wait_held(["worker-000"], 1)
        os.kill(pids[0], signal.SIGKILL)
        gate.open(10_000)

    def on_start(actors: list) -> None:
        pids.append(ray.get(actors[0].pid.remote()))
        _in_thread(kill)(actors)

    assert _generate(_async_config(tiny_config), out, on_start) == 0
    summary = capsys.readouterr().out
    assert _check(out, summary) == 6
    assert [line["generate"]["episode"] for line in sidecar(out)] == list(range(6))
    row0 = next(line.split() for line in summary.splitlines() if re.match(r"\s+0\s+\d+", line))
    assert row0[4] == "1", summary  # worker 0: one restart


def test_a_worker_killed_while_closing_loses_nothing_and_the_table_matches(
    tmp_path: Path, tiny_config: Any, monkeypatch: Any, capsys: Any
) -> None:
    import ray

    out, pids = tmp_path / "merged", []
    real_close = run.close_workers

    def close_killing_one(actors: list, *args: Any) -> None:
        pids.append(ray.get(actors[1].pid.remote()))
        ref = actors[1].close.remote()  # worker 1 starts closing its shard, and is killed
        os.kill(pids[0], signal.SIGKILL)
        ray.wait([ref], timeout=60)
        real_close(actors, *args)

    monkeypatch.setattr(run, "close_workers", close_killing_one)
    code = _generate(_async_config(tiny_config), out)
    summary = capsys.readouterr().out
    assert pids, "the close hook did not run"
    assert code == 0, summary
    assert _check(out, summary) == 6


def test_ctrl_c_of_the_driver_merges_every_finished_episode_with_true_counts(
    tmp_path: Path, tiny_config: Any, monkeypatch: Any, capsys: Any
) -> None:
    gate, out = Gate(tmp_path, monkeypatch, allowed=1), tmp_path / "merged"

    def interrupt() -> None:  # each worker has one episode saved and one finished in its writer
        gate.wait_held(["worker-000", "worker-001"], 1)
        gate.open(10_000)
        os.kill(os.getpid(), signal.SIGINT)

    config = _async_config(tiny_config, max_episode_steps=40)  # long episodes: the run is not over yet
    assert _generate(config, out, _in_thread(interrupt)) == 130
    summary = capsys.readouterr().out
    assert "stopped      early: interrupted (Ctrl-C)" in summary
    merged = _check(out, summary)
    assert 4 <= merged < 6, summary  # both finished episodes of each worker were flushed and merged
    assert re.search(rf"not saved\s+{6 - merged} episode\(s\)", summary), summary
    # resuming: the same run with the kept shards runs only the missing episodes
    again = tmp_path / "again"
    argv = ["--gym_config", config, "--episodes", "6", "--workers", "2", "--seed", "3", "--output", str(again)]
    assert cli.main([*argv, "--quiet", "--shards", str(out.with_name("merged.shards"))]) == 0
    summary = capsys.readouterr().out
    assert f"resumed      {merged} episode(s)" in summary, summary
    assert _check(again, summary) == 6
    assert [line["generate"]["episode"] for line in sidecar(again)] == list(range(6))


def _driver(config: str, out: Path, *extra: str) -> subprocess.Popen:
    """``embodichain generate`` in its own process (output in ``<out>.stdout`` and ``<out>.stderr``)."""
    argv = ["--gym_config", config, "--episodes", "6", "--workers", "2", "--seed", "3", "--output", str(out)]
    with open(f"{out}.stdout", "w") as stdout, open(f"{out}.stderr", "w") as stderr:
        return subprocess.Popen(
            [sys.executable, "-m", "embodichain_ray.cli", *argv, "--keep-shards", *extra], stdout=stdout, stderr=stderr
        )


def _ray_of(proc: subprocess.Popen) -> dict[int, str]:
    found = ray_processes(proc.pid)
    assert any("raylet" in cmd for cmd in found.values()), found  # the embedded Ray runs under the driver
    return found


def test_sigterm_of_the_driver_stops_it_like_ctrl_c(tmp_path: Path, tiny_config: Any, monkeypatch: Any) -> None:
    gate, out = Gate(tmp_path, monkeypatch, allowed=1), tmp_path / "merged"
    config = _async_config(tiny_config, max_episode_steps=40)  # long episodes: the run is not over yet
    proc = _driver(config, out, "--progress-every", "0.5")  # no terminal: plain progress lines
    gate.wait_held(["worker-000", "worker-001"], 1)  # each worker: one episode saved, one in its writer
    ray = _ray_of(proc)
    gate.open(10_000)
    proc.send_signal(signal.SIGTERM)
    code = proc.wait(timeout=300)
    summary, errors = Path(f"{out}.stdout").read_text(), Path(f"{out}.stderr").read_text()
    assert code == 143, summary + errors
    assert "SIGTERM received" not in errors, errors  # no crash dump of Ray's core worker
    assert "Traceback" not in errors, errors
    assert "terminated (SIGTERM); the workers finish their writes" in errors, errors
    assert "stopped      early: terminated (SIGTERM)" in summary, summary
    assert re.search(r"generate: [1-6]/6 episode\(s\) saved \(\d+%\), [\d.]+ episode\(s\)/s, ETA", summary), summary
    merged = _check(out, summary)
    assert 4 <= merged < 6, summary  # the episodes the writers held were flushed and merged
    assert still_running(ray, within=10) == {}


def test_sigkill_of_the_driver_leaves_no_ray_process_and_the_shards_keep_every_saved_episode(
    tmp_path: Path, tiny_config: Any, monkeypatch: Any, capsys: Any
) -> None:
    gate, out = Gate(tmp_path, monkeypatch, allowed=1), tmp_path / "merged"
    config = _async_config(tiny_config, max_episode_steps=40)
    proc = _driver(config, out, "--quiet")
    gate.wait_held(["worker-000", "worker-001"], 1)
    ray = _ray_of(proc)
    writers = ray_processes(proc.pid, writers=True)
    assert len(writers) == 2, writers
    proc.kill()
    proc.wait(timeout=60)
    assert still_running(ray, within=10) == {}  # the raylet's agents included
    gate.open(10_000)  # the orphaned writers write the episode each one held, finalize and exit
    assert still_running(writers, within=120) == {}
    shards = out.with_name("merged.shards")
    argv = ["--gym_config", config, "--episodes", "6", "--workers", "2", "--seed", "3", "--output", str(out)]
    code = cli.main([*argv, "--quiet", "--merge-only", "--shards", str(shards)])
    summary = capsys.readouterr().out
    merged = int(re.search(r"episodes\s+(\d+)/6 merged", summary).group(1))
    assert load(out).num_episodes == merged, summary
    assert merged >= 4, summary  # each worker's saved episode and the one its writer held (more if sent)
    assert code == (0 if merged == 6 else 1), summary
