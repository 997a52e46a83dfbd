"""Shards without a shared folder, and the merge while generating: a storage URI (fsspec's
in-memory filesystem) carrying batches to the driver's copy of a shard, episodes merged in
any arrival order giving the dataset a merge at the end gives, Ray's object store on a
local Ray, and the bad inputs that stop a run before any episode runs."""

from __future__ import annotations

import hashlib
import time
from pathlib import Path
from typing import Any

import numpy as np
from embodichain_ray import cli
from embodichain_ray.merge import StreamingMerge, merge_episodes
from embodichain_ray.shards import scan_shards
from embodichain_ray.spec import GenerateSpec, episode_seed, seed_table
from embodichain_ray.storage import open_storage
from embodichain_ray.transport import receive
from embodichain_ray.worker import EpisodeWorker
from ray_helpers import episode_arrays, generate_spec, load, sidecar


def _spec(tmp_path: Path, config: str, **kw: Any) -> GenerateSpec:
    return generate_spec(tmp_path, config, **{"episodes": 7, "workers": 2, "seed": 3, **kw})


def _digests(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest() for p in root.rglob("*") if p.is_file()
    }


def test_episodes_merged_as_they_arrive_equal_the_merge_at_the_end(tmp_path: Path, tiny_config: Any) -> None:
    spec = _spec(tmp_path, tiny_config())
    workers = [EpisodeWorker(spec, 0), EpisodeWorker(spec, 1)]
    try:
        workers[0].run([0, 3, 4])
        workers[1].run([1, 2, 6, 5])
    finally:
        for worker in workers:
            worker.close()
    scan = scan_shards(spec.shards, seed_table(spec.seed, 8, 1))
    assert sorted(scan.episodes) == list(range(7))
    merge_episodes([scan.episodes[k] for k in range(7)], tmp_path / "at_the_end", per_file=3)
    streaming = StreamingMerge(tmp_path / "streaming", per_file=3)
    for k in (6, 2, 5):
        streaming.add(scan.episodes[k])
    streaming.skip(7)  # an episode that failed every attempt: no hole at the end
    streaming.add(scan.episodes[0])
    deadline = time.monotonic() + 60
    while not (tmp_path / ".streaming.merging" / "data").exists() and time.monotonic() < deadline:
        time.sleep(0.05)  # episode 0 is merged before the rest arrives
    assert (tmp_path / ".streaming.merging" / "data").exists()
    assert not (tmp_path / "streaming").exists()
    for k in (1, 4, 3):
        streaming.add(scan.episodes[k])
    assert not streaming.add(scan.episodes[3])  # a second copy of an episode is ignored
    assert streaming.finish() == 7
    assert not (tmp_path / ".streaming.merging").exists()
    assert _digests(tmp_path / "streaming") == _digests(tmp_path / "at_the_end")  # the same files, byte for byte
    assert [line["generate"]["episode"] for line in sidecar(tmp_path / "streaming")] == list(range(7))


def test_a_storage_uri_carries_each_batch_to_the_drivers_copy_of_the_shard(tmp_path: Path, tiny_config: Any) -> None:
    uri = f"memory://embodichain-test/{tmp_path.name}"
    scratch, driver = tmp_path / "node-scratch", tmp_path / "driver-shards"
    spec = _spec(tmp_path, tiny_config(), transport=uri, scratch=str(scratch), shards=driver)
    worker = EpisodeWorker(spec, 0)
    try:
        first = worker.run([1, 0]).delivery
        assert first is not None
        assert [r["episode_seed"] for r in first.records] == [episode_seed(3, 1), episode_seed(3, 0)]
        assert [item.path for item in first.files][-1] == "meta/info.json"  # the commit point goes last
        assert any(item.stored for item in first.files)  # data and videos went through storage
        receive(first, driver, uri)
        second = worker.run([2]).delivery
        assert second is not None
        assert [r["episode_seed"] for r in second.records] == [episode_seed(3, 2)]
        root = receive(second, driver, uri)
        recorded = Path(worker._shard_root())
    finally:
        worker.close()
    assert scratch in recorded.parents
    assert driver not in recorded.parents
    assert not recorded.exists()  # the node's scratch folder is removed when the worker closes
    fs, base = open_storage(uri)
    from pyarrow.fs import FileSelector

    assert [i.path for i in fs.get_file_info(FileSelector(base, recursive=True, allow_not_found=True)) if i.size] == []
    assert not (root / ".embodichain_staging").exists()
    scan = scan_shards(driver, seed_table(3, 3, 1))
    assert sorted(scan.episodes) == [0, 1, 2]
    merge_episodes([scan.episodes[k] for k in range(3)], tmp_path / "merged")
    ds = load(tmp_path / "merged")
    assert (ds.num_episodes, ds.num_frames) == (3, 30)
    copy = episode_arrays(root)
    merged = episode_arrays(tmp_path / "merged")
    for k, shard_index in enumerate([1, 0, 2]):
        np.testing.assert_array_equal(merged[k]["action"], copy[shard_index]["action"])


def _argv(config: str, out: Path) -> list[str]:
    return ["--gym_config", config, "--episodes", "4", "--workers", "2", "--seed", "3", "--output", str(out), "--quiet"]


def test_an_unreachable_storage_uri_or_output_stops_before_ray_starts(
    tmp_path: Path, tiny_config: Any, capsys: Any
) -> None:
    import sys

    config, out = tiny_config(), tmp_path / "never"
    assert cli.main([*_argv(config, out), "--transport", "file:///proc/embodichain-no-such-place"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith("embodichain generate: config error")
    assert "--transport" in err
    assert "cannot write to file:///proc/embodichain-no-such-place" in err
    assert cli.main([*_argv(config, out), "--transport", "nosuchscheme://bucket/x"]) == 2
    assert "cannot open nosuchscheme://bucket/x" in capsys.readouterr().err
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert cli.main(_argv(config, blocker / "out")) == 2
    err = capsys.readouterr().err.strip()
    assert "--output" in err
    assert f"{blocker} is not a folder" in err
    assert not out.exists()
    assert not out.with_name("never.shards").exists()
    assert "ray" not in sys.modules or not sys.modules["ray"].is_initialized()


def test_the_object_store_carries_the_shards_of_two_workers(tmp_path: Path, tiny_config: Any, capsys: Any) -> None:
    out, scratch = tmp_path / "merged", tmp_path / "scratch"
    assert cli.main([*_argv(tiny_config(), out), "--transport", "ray", "--scratch", str(scratch)]) == 0
    assert "4/4 merged" in capsys.readouterr().out
    ds = load(out)
    assert (ds.num_episodes, ds.num_frames) == (4, 40)
    assert [line["episode_seed"] for line in sidecar(out)] == [episode_seed(3, k) for k in range(4)]
    assert not out.with_name("merged.shards").exists()  # merged: the driver's copies are removed
    assert not any(p.is_file() for p in scratch.rglob("*"))  # each worker removed its scratch folder
