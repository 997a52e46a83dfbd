"""``embodichain generate``'s merge: merging at the end against merging while generating.

Synthetic episodes (``--frames`` frames each of a 6-dim state and action and one 32x32
colour camera encoded as AV1 video) are written with the project's ``DatasetWriter`` into
``--shards`` shards, interleaved as workers take them from the queue (shard ``s`` holds
episodes ``s``, ``s + W``, ...), each recorded with its run episode seed. Then:

* **at the end** (``embodichain generate`` before the merge ran while generating):
  ``merge_episodes`` of every episode once the last one exists; the end of the run waits
  for all of it.
* **while generating** (``StreamingMerge``, what a run does now): the episodes are handed
  to the merge in the order and at the rate batches return (``--rate`` episodes/s, as
  ``W`` workers would deliver them); the end of the run waits from the last episode until
  ``finish()`` has moved the complete dataset into place.

Both results are loaded with ``LeRobotDataset`` (time reported) and compared file by file
(they must be identical). ``--rate`` defaults to 4 episodes/s, about 24 workers at the
data-generation job's 10 episodes/min each; the merge keeps up while its per-episode cost is
below ``1 / rate``.

Usage:
    python benchmarks/generate_merge.py [--episodes 1000] [--shards 4] [--rate 4] \\
        [--out benchmarks/results/generate_merge.json]
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import machine_info, write_json

DEFAULT_OUT = os.path.join("benchmarks", "results", "generate_merge.json")
FEATURES = {
    "observation.state": {"dtype": "float32", "shape": (6,), "names": None},
    "action": {"dtype": "float32", "shape": (6,), "names": None},
    "observation.images.cam": {"dtype": "video", "shape": (32, 32, 3), "names": ["height", "width", "channels"]},
}


def write_shards(folder: Path, episodes: int, shards: int, frames: int) -> list[Any]:
    """Write the synthetic shards; the run's episodes (``ShardEpisode``) in episode order."""
    import numpy as np

    from embodichain_lerobot.writer import DatasetWriter
    from embodichain_ray.shards import scan_shards
    from embodichain_ray.spec import episode_seed, seed_table

    rng = np.random.default_rng(0)
    for s in range(shards):
        (folder / f"worker-{s:03d}" / "shard_000").mkdir(parents=True)
    writers = [
        DatasetWriter(folder / f"worker-{s:03d}" / "shard_000", 30, FEATURES, "synthetic", True) for s in range(shards)
    ]
    try:
        for k in range(episodes):
            batch = [
                {
                    "observation.state": rng.standard_normal(6).astype("float32"),
                    "action": rng.standard_normal(6).astype("float32"),
                    "observation.images.cam": rng.integers(0, 255, (32, 32, 3), dtype="uint8"),
                    "task": "synthetic",
                }
                for _ in range(frames)
            ]
            writers[k % shards].write_episode(batch, {"episode_seed": episode_seed(0, k)})
    finally:
        for writer in writers:
            writer.finalize()
    scan = scan_shards(folder, seed_table(0, episodes, 1))
    return [scan.episodes[k] for k in range(episodes)]


def at_the_end(ordered: list[Any], output: Path) -> float:
    """Seconds of ``merge_episodes`` of every episode (the old end-of-run wait)."""
    from embodichain_ray.merge import merge_episodes

    started = time.perf_counter()
    merge_episodes(ordered, output)
    return time.perf_counter() - started


def while_generating(ordered: list[Any], output: Path, rate: float, batch: int) -> dict[str, float]:
    """Hand the episodes to a ``StreamingMerge`` at ``rate`` episodes/s, ``batch`` at a time."""
    from embodichain_ray.merge import StreamingMerge

    merge = StreamingMerge(output)
    started = time.perf_counter()
    for i in range(0, len(ordered), batch):
        due = started + i / rate
        time.sleep(max(0.0, due - time.perf_counter()))
        for ep in ordered[i : i + batch]:
            merge.add(ep)
    last = time.perf_counter()
    merge.finish()
    done = time.perf_counter()
    return {"arrivals_s": last - started, "after_last_s": done - last}


def load_seconds(root: Path) -> tuple[float, int]:
    """Seconds to open the dataset with ``LeRobotDataset`` and read its last frame; its episodes."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    started = time.perf_counter()
    ds = LeRobotDataset(f"local/{root.name}", root=root, video_backend="pyav")
    ds[len(ds) - 1]
    return time.perf_counter() - started, ds.num_episodes


def digest(root: Path) -> dict[str, str]:
    """SHA-256 of every file of a dataset, by relative path."""
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest() for p in root.rglob("*") if p.is_file()
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=1000, help="synthetic episodes (default 1000)")
    parser.add_argument("--shards", type=int, default=4, help="shards, as workers (default 4)")
    parser.add_argument("--frames", type=int, default=10, help="frames per episode (default 10)")
    parser.add_argument("--rate", type=float, default=4.0, help="episodes/s reaching the merge (default 4)")
    parser.add_argument("--out", default=DEFAULT_OUT, help=f"JSON results (default {DEFAULT_OUT})")
    args = parser.parse_args()
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("SVT_LOG", "1")
    with tempfile.TemporaryDirectory(prefix="generate_merge_") as tmp:
        folder = Path(tmp)
        started = time.perf_counter()
        ordered = write_shards(folder / "shards", args.episodes, args.shards, args.frames)
        write_s = time.perf_counter() - started
        end_s = at_the_end(ordered, folder / "at_the_end")
        streamed = while_generating(ordered, folder / "streaming", args.rate, args.shards)
        load_end, n_end = load_seconds(folder / "at_the_end")
        load_stream, n_stream = load_seconds(folder / "streaming")
        identical = digest(folder / "at_the_end") == digest(folder / "streaming")
    result = {
        "episodes": args.episodes,
        "frames_per_episode": args.frames,
        "shards": args.shards,
        "rate_episodes_per_s": args.rate,
        "write_s": write_s,
        "merge_at_the_end_s": end_s,
        "merge_ms_per_episode": 1000.0 * end_s / args.episodes,
        "streaming_arrivals_s": streamed["arrivals_s"],
        "streaming_after_last_s": streamed["after_last_s"],
        "load_s": {"at_the_end": load_end, "streaming": load_stream},
        "loaded_episodes": {"at_the_end": n_end, "streaming": n_stream},
        "identical_files": identical,
        "machine": machine_info(),
    }
    print(
        f"{args.episodes} synthetic episodes ({args.frames} frames, {args.shards} shards), written in {write_s:.1f} s"
    )
    print(
        f"merge at the end:       {end_s:.1f} s ({result['merge_ms_per_episode']:.0f} ms/episode) after the last episode"
    )
    print(
        f"merge while generating: {streamed['after_last_s']:.2f} s after the last episode "
        f"(episodes arriving at {args.rate:g}/s over {streamed['arrivals_s']:.1f} s)"
    )
    print(f"load + last frame:      {load_end:.2f} s / {load_stream:.2f} s; identical files: {identical}")
    print(f"results: {write_json(args.out, result)}")
    return 0 if identical and n_end == n_stream == args.episodes else 1


if __name__ == "__main__":
    sys.exit(main())
