"""Without Ray: episode seeds, the worker's retries and the ordered merge of shards."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from embodichain_ray.merge import merge_episodes
from embodichain_ray.shards import scan_shards
from embodichain_ray.spec import episode_seed, seed_table
from embodichain_ray.worker import EpisodeWorker
from ray_helpers import episode_arrays, generate_spec, load, sidecar

from embodichain_core.envs.episode_rng import derive_seed


def test_episode_seeds_are_a_function_of_seed_episode_and_attempt() -> None:
    assert episode_seed(7, 3) == int(derive_seed(7, 3))
    assert episode_seed(7, 3, 2) == int(derive_seed(7, 3, 2))
    table = seed_table(7, 50, 3)
    assert len(table) == 150
    assert table[episode_seed(7, 49, 2)] == (49, 2)
    assert episode_seed(8, 3) not in table


def test_failed_demos_are_retried_with_the_next_attempts_seed(tmp_path: Path, tiny_config: Any) -> None:
    config = tiny_config(demo_max_attempts=3)  # 10-step episodes: the demo never succeeds
    worker = EpisodeWorker(generate_spec(tmp_path, config), 0)
    worker.plan.keep_failed = False  # as if the recorder kept successes only
    seen: list = []
    reset = worker.env.reset

    def spy(**kw: Any) -> Any:
        seeds = (kw.get("options") or {}).get("episode_seeds")
        if seeds is not None:
            seen.append([int(s) for s in seeds])
        return reset(**kw)

    worker.env.reset = spy
    try:
        result = worker.run([4])
    finally:
        worker.close()
    assert [(o.episode, o.attempts, o.saved) for o in result.outcomes] == [(4, 3, False)]
    assert result.failed_attempts == 3
    assert seen == [[episode_seed(7, 4, a)] for a in range(3)]


def test_shard_episodes_merge_in_episode_order_with_their_metadata(tmp_path: Path, tiny_config: Any) -> None:
    spec = generate_spec(tmp_path, tiny_config())
    worker = EpisodeWorker(spec, 0)
    try:
        worker.run([3, 1])
        worker.run([0, 2, 1])  # episode 1 twice: the second copy is a duplicate
    finally:
        shard = worker.close()
    scan = scan_shards(spec.shards, seed_table(spec.seed, 4, 2))
    assert sorted(scan.episodes) == [0, 1, 2, 3]
    assert scan.duplicates == 1
    assert scan.unknown == 0
    merge_episodes([scan.episodes[k] for k in range(4)], spec.output)
    merged = load(spec.output)
    assert merged.num_episodes == 4
    assert merged.num_frames == 40
    lines = sidecar(spec.output)
    assert [line["generate"]["episode"] for line in lines] == [0, 1, 2, 3]
    assert [line["lerobot_episode_index"] for line in lines] == [0, 1, 2, 3]
    assert [line["episode_seed"] for line in lines] == [episode_seed(7, k) for k in range(4)]
    source, result = episode_arrays(Path(shard)), episode_arrays(spec.output)
    for k, shard_index in enumerate([2, 1, 3, 0]):  # the shard holds 3, 1, 0, 2, 1
        for key in ("observation.state", "action"):
            np.testing.assert_array_equal(result[k][key], source[shard_index][key])
    frame = merged[15]  # episode 1, frame 5: its video frame decodes
    assert int(frame["episode_index"]) == 1
    assert tuple(frame["observation.images.eye_in_head"].shape) == (3, 64, 64)
    with pytest.raises(FileExistsError):
        merge_episodes([scan.episodes[0]], spec.output)


def test_the_merge_starts_new_files_every_per_file_episodes(tmp_path: Path, tiny_config: Any) -> None:
    spec = generate_spec(tmp_path, tiny_config())
    worker = EpisodeWorker(spec, 0)
    try:
        worker.run([2, 0, 1])
    finally:
        worker.close()
    scan = scan_shards(spec.shards, seed_table(spec.seed, 3, 2))
    ordered = [scan.episodes[k] for k in range(3)]
    merge_episodes(ordered, tmp_path / "one_file")
    merge_episodes(ordered, tmp_path / "two_per_file", per_file=2)
    assert len(list((tmp_path / "two_per_file" / "data").rglob("*.parquet"))) == 2
    assert len(list((tmp_path / "two_per_file" / "videos").rglob("*.mp4"))) == 4  # 2 cameras x 2 files
    a, b = load(tmp_path / "one_file"), load(tmp_path / "two_per_file")
    for i in (0, 15, 29):  # frames of episodes 0, 1 (a new file) and 2
        for key in ("observation.state", "action", "episode_index", "index"):
            assert np.array_equal(a[i][key].numpy(), b[i][key].numpy()), (i, key)
        assert np.allclose(
            a[i]["observation.images.eye_in_head"].numpy(), b[i]["observation.images.eye_in_head"].numpy(), atol=1e-6
        )


def test_merge_only_merges_what_the_shards_hold_without_starting_ray(
    tmp_path: Path, tiny_config: Any, capsys: Any
) -> None:
    import sys

    from embodichain_ray import cli

    config = tiny_config()
    spec = generate_spec(tmp_path, config)
    worker = EpisodeWorker(spec, 0)
    try:
        worker.run([1, 0, 2])
    finally:
        worker.close()
    argv = ["--gym_config", config, "--seed", "7", "--merge-only", "--shards", str(spec.shards), "--quiet"]
    assert cli.main([*argv, "--episodes", "4", "--output", str(tmp_path / "partial")]) == 1  # 3 of 4
    assert "3/4 merged" in capsys.readouterr().out
    assert spec.shards.is_dir()
    assert cli.main([*argv, "--episodes", "3", "--output", str(tmp_path / "all")]) == 0
    assert [line["generate"]["episode"] for line in sidecar(tmp_path / "all")] == [0, 1, 2]
    assert load(tmp_path / "all").num_episodes == 3
    assert not spec.shards.exists()
    assert "ray" not in sys.modules or not sys.modules["ray"].is_initialized()
