"""``embodichain generate`` on a Ray cluster of several nodes without a shared filesystem,
simulated on one machine with ``ray.cluster_utils.Cluster``: a head node without CPUs (the
driver's) and worker nodes of one CPU each, all on 127.0.0.1, each with its own scratch
folder (``EMBODICHAIN_GENERATE_SCRATCH`` in that node's environment) that the driver never
reads. A node removed mid-run (its scratch folder deleted with it), a run stopped and resumed
with ``--shards`` over a storage URI, and a node without the task's plugin."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from embodichain_ray import cli
from embodichain_ray.spec import episode_seed
from embodichain_ray.transport import SCRATCH_ENV
from ray_helpers import load, sidecar

pytestmark = pytest.mark.slow  # a Ray cluster of 3-4 nodes and a two-worker run each (~1-2 min on 2 cores)


@pytest.fixture
def cluster(monkeypatch: Any) -> Iterator[Callable[[list[dict]], tuple[Any, list]]]:
    """``cluster([env of node 1, ...]) -> (Cluster, nodes)``: a head without CPUs and one node
    of one CPU per environment (its variables set while the node starts), all on 127.0.0.1."""
    import ray
    import ray._private.ray_constants as ray_constants
    from ray.cluster_utils import Cluster

    import ray._private.services as services

    temp = tempfile.mkdtemp(prefix="ecr-")  # Ray's files and sockets (short paths), not /tmp/ray
    monkeypatch.setenv("RAY_TMPDIR", temp)
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    # on a loaded machine a node's agents take well over Ray's 30 s to start: wait for them
    monkeypatch.setenv("RAY_raylet_start_wait_time_s", "180")
    # a busy node answers its health checks late: give each check a minute before it counts as
    # missed (a removed node refuses the connection at once, so it is still found dead in seconds)
    monkeypatch.setenv("RAY_health_check_timeout_ms", "60000")
    get_node = services.get_node

    def patient_get_node(*args: Any, **kwargs: Any) -> Any:
        deadline = time.monotonic() + 180
        while True:
            try:
                return get_node(*args, **kwargs)
            except RuntimeError:  # not registered yet
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)

    monkeypatch.setattr(services, "get_node", patient_get_node)
    made: list = []

    def make(nodes: list[dict]) -> tuple[Any, list]:
        head = {"num_cpus": 0, "node_ip_address": "127.0.0.1", "include_dashboard": False}
        made.append(Cluster(initialize_head=True, head_node_args=head))
        handles = []
        for env in nodes:
            for key, value in env.items():
                monkeypatch.setenv(key, value)
            handles.append(made[-1].add_node(num_cpus=1, node_ip_address="127.0.0.1"))
            for key in env:
                monkeypatch.delenv(key)
        made[-1].wait_for_nodes()
        # the driver joins on 127.0.0.1 (Ray would otherwise swap it for the host's address)
        monkeypatch.setattr(ray_constants, "ENABLE_RAY_CLUSTER", False)
        return made[-1], handles

    yield make
    if ray.is_initialized():
        ray.shutdown()
    for c in made:
        c.shutdown()
    shutil.rmtree(temp, ignore_errors=True)


def _argv(config: str, out: Path, address: str, *extra: str) -> list[str]:
    argv = ["--gym_config", config, "--episodes", "6", "--workers", "2", "--seed", "3", "--output", str(out)]
    return [*argv, "--ray-address", address, "--quiet", *extra]


def _driver_episodes(shards: Path, worker: str = "*") -> int:
    """Episodes the driver's copies of the shards hold (of one worker, or of all)."""
    infos = shards.glob(f"{worker}/*/meta/info.json")
    return sum(int(json.loads(p.read_text()).get("total_episodes", 0)) for p in infos)


def _when(condition: Callable[[], bool], then: Callable[[], None]) -> None:
    """Run ``then`` in a thread once ``condition`` holds (polled; at most 300 s)."""

    def watch() -> None:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            if condition():
                then()
                return
            time.sleep(0.05)

    threading.Thread(target=watch, daemon=True).start()


def _check_complete(out: Path, frames: int) -> None:
    ds = load(out)
    assert (ds.num_episodes, ds.num_frames) == (6, 6 * frames)
    lines = sidecar(out)
    assert [line["generate"]["episode"] for line in lines] == list(range(6))
    assert [line["episode_seed"] for line in lines] == [episode_seed(3, k) for k in range(6)]


def test_a_node_lost_mid_run_has_its_batches_run_again_on_another_node(
    tmp_path: Path, tiny_config: Any, cluster: Any, capsys: Any
) -> None:
    import ray

    scratch = [tmp_path / f"node{i}-scratch" for i in range(3)]
    head, nodes = cluster([{SCRATCH_ENV: str(s)} for s in scratch])  # 3 nodes for 2 workers: one to restart on
    out, shards, lost = tmp_path / "merged", tmp_path / "driver-shards", []

    def remove(node_id: str, worker_pid: int) -> None:
        index = next(i for i, n in enumerate(nodes) if n.node_id == node_id)
        head.remove_node(nodes[index], allow_graceful=False)
        # the lost machine's processes and disk go together: on one machine the worker would
        # outlive its raylet for a moment and see its scratch folder vanish (a disk error)
        try:
            os.kill(worker_pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        shutil.rmtree(scratch[index], ignore_errors=True)
        lost.append(index)

    def on_start(actors: list) -> None:
        node_id, pid = ray.get([actors[0].node_id.remote(), actors[0].pid.remote()])
        _when(lambda: _driver_episodes(shards, "worker-000") >= 1, lambda: remove(node_id, pid))

    config = tiny_config(max_episode_steps=40)  # ~1 s episodes: the node goes mid-run
    argv = _argv(config, out, head.address, "--transport", "ray", "--shards", str(shards))
    assert cli.main(argv, on_start=on_start) == 0
    captured = capsys.readouterr()
    assert lost, "the node was never removed"
    assert re.search(r"worker 0 died while running episode\(s\) \d+ .*they run again", captured.err), captured.err
    assert "6/6 merged" in captured.out
    assert "lost " not in captured.out
    rows = [line.split() for line in captured.out.splitlines() if line.strip().startswith("0 ")]
    assert rows[0][4] == "1", captured.out  # worker 0 restarts once (on the spare node)
    assert not scratch[lost[0]].exists()
    _check_complete(out, 40)


def test_a_run_stopped_over_a_storage_uri_resumes_with_shards(
    tmp_path: Path, tiny_config: Any, cluster: Any, capsys: Any
) -> None:
    scratch = [tmp_path / f"node{i}-scratch" for i in range(2)]
    head, _ = cluster([{SCRATCH_ENV: str(s)} for s in scratch])
    uri, shards, config = (tmp_path / "bucket").as_uri(), tmp_path / "driver-shards", tiny_config()
    extra = ("--transport", uri, "--shards", str(shards))
    _when(lambda: _driver_episodes(shards) >= 2, lambda: os.kill(os.getpid(), signal.SIGINT))
    assert cli.main(_argv(config, tmp_path / "first", head.address, *extra)) == 130
    first = capsys.readouterr().out
    partial = load(tmp_path / "first").num_episodes
    assert 2 <= partial < 6, first
    assert cli.main(_argv(config, tmp_path / "second", head.address, *extra)) == 0
    second = capsys.readouterr().out
    assert re.search(r"\d+ episode\(s\) of this run are already in", second), second
    _check_complete(tmp_path / "second", 10)
    assert not shards.exists()  # complete: the driver's copies are removed
    assert not any(p.is_file() for p in (tmp_path / "bucket").rglob("*"))  # every stored file was fetched


def test_a_node_without_the_tasks_plugin_stops_the_run_before_any_episode(
    tmp_path: Path, tiny_config: Any, cluster: Any, capsys: Any
) -> None:
    scratch = [tmp_path / f"node{i}-scratch" for i in range(2)]
    envs = [
        {SCRATCH_ENV: str(scratch[0])},
        {SCRATCH_ENV: str(scratch[1]), "EMBODICHAIN_BLOCK_PLUGINS": "embodichain-tasks"},
    ]
    head, _ = cluster(envs)
    out = tmp_path / "never"
    assert cli.main(_argv(tiny_config(), out, head.address, "--transport", "ray")) == 2
    captured = capsys.readouterr()
    said = [line for line in captured.err.splitlines() if line.startswith("embodichain generate:")]
    assert len(said) == 1, captured.err
    assert re.search(r"worker [01] cannot start on node 127\.0\.0\.1 \(pid \d+\): .*PickFork-v1", said[0]), said[0]
    assert "plugins" in said[0]
    assert captured.out == ""  # no summary: nothing ran
    assert not out.exists()
    assert not (tmp_path / ".never.merging").exists()
    assert not out.with_name("never.shards").exists()
    assert not any(p.is_file() for s in scratch for p in s.rglob("*"))
