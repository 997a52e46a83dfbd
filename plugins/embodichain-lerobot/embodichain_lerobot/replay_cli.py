"""``embodichain dataset replay``: the command around :class:`~embodichain_lerobot.replay.Replayer`.

Prints, per episode, the largest error of every compared feature (and the lowest PSNR
of every camera feature), then one line per episode past tolerance naming the frame and
feature where it first went past; ``--json`` writes the same. Exit code 0 when every
episode replays within tolerance, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from embodichain_lerobot.replay import EpisodeReplay, Replayer

__all__ = ["format_replay", "run_replay"]


def _episodes(args: argparse.Namespace, total: int) -> list[int]:
    if args.all:
        return list(range(total))
    episode = 0 if args.episode is None else int(args.episode)
    if not 0 <= episode < total:
        raise IndexError(f"episode {episode} is out of range: the dataset has {total} episode(s)")
    return [episode]


def _seeds(root: Path, total: int) -> dict[int, Any]:
    """Each published episode's recorded seed (``None`` when it has none)."""
    from embodichain_lerobot.reading import read_sidecar

    out: dict[int, Any] = {}
    for position, record in enumerate(read_sidecar(root, total)):
        out[int(record.get("lerobot_episode_index", position))] = record.get("episode_seed")
    return out


def format_replay(result: EpisodeReplay, atol: float, min_psnr: float) -> str:
    """One episode's block: a line per feature, then the verdict."""
    worst = max(result.max_error.values(), default=0.0)
    lines = [f"episode {result.episode}  seed {result.seed}  frames {result.frames}  max error {worst:.3g}"]
    for name, err in sorted(result.max_error.items()):
        lines.append(f"  {name:<40} max error {err:.3g}")
    for name, db in sorted(result.min_psnr.items()):
        shown = "exact" if db == float("inf") else f"{db:.1f} dB"
        lines.append(f"  {name:<40} min PSNR  {shown}")
    if result.ok:
        lines.append(f"  ok (atol {atol:g}, PSNR >= {min_psnr:g} dB)")
    for f in result.failures:
        what = f"PSNR {f['error']:.1f} dB" if f["feature"] in result.min_psnr else f"error {f['error']:.3g}"
        lines.append(f"  FAILED: episode {result.episode}, frame {f['frame']}, feature {f['feature']}: {what}")
    return "\n".join(lines)


def run_replay(args: argparse.Namespace) -> int:
    """Replay what ``args`` selects; 0 when every episode is within tolerance, else 1."""
    from embodichain_lerobot.env_meta import version_mismatches
    from embodichain_lerobot.reading import check_dataset_dir

    root = check_dataset_dir(args.path)
    total = int(json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))["total_episodes"])
    episodes = _episodes(args, total)
    replayer = Replayer(root, args.atol, args.min_psnr, args.image_frames)
    mismatched = version_mismatches(replayer.meta)
    if mismatched:
        print(
            "embodichain dataset replay: warning: the dataset was recorded with other versions ("
            + "; ".join(mismatched)
            + "); the replay may differ from the recording",
            file=sys.stderr,
        )
    seeds, results = _seeds(root, total), []
    try:
        for episode in episodes:
            result = replayer.replay(episode, seeds.get(episode))
            results.append(result)
            print(format_replay(result, replayer.atol, replayer.min_psnr), flush=True)
    finally:
        replayer.close()
    failed = [r.episode for r in results if not r.ok]
    print(f"replayed {len(results)} episode(s): {len(results) - len(failed)} within tolerance, {len(failed)} not")
    if args.json:
        data = {
            "dataset": str(root),
            "task_id": replayer.meta.get("task_id"),
            "backend": replayer.meta.get("backend"),
            "atol": replayer.atol,
            "min_psnr": replayer.min_psnr,
            "version_mismatches": mismatched,
            "ok": not failed,
            "episodes": [r.to_dict() for r in results],
        }
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    return 1 if failed else 0
