"""``embodichain dataset``: inspect recorded LeRobot datasets (offline).

Commands:
    info PATH [--json] [--episodes]
        episodes, frames, fps, tasks, features (dtype and shape) of a dataset folder,
        then one line per episode (length, success, env, episode seed): the first
        20, every one with ``--episodes``.
        A folder left by a recording that saved no episode is reported as
        incomplete (exit 2), never read as a dataset.
    preview PATH --episode N [--out DIR] [--format png|mp4] [--frames K]
        a contact sheet PNG (or an mp4) of the episode's camera streams and a
        plot of its state and action over time.
    replay PATH [--episode N | --all] [--json FILE] [--atol X] [--min_psnr DB] [--image_frames K]
        rebuild the env from ``meta/embodichain_env.json``, replay each episode's recorded
        actions from its recorded seed and compare the re-simulated features frame by
        frame (:mod:`embodichain_lerobot.replay`); exit 1 when one is past tolerance.
    view PATH [--episode N] [--viewer auto|native|browser] [--port P] [--speed X] [--exit]
        the same replay of one episode in the viewer, the recorded camera frames beside
        the re-rendered ones (needs the embodichain-viewer plugin).

Exit codes: 0 success, 1 the command failed, 2 usage error or not a dataset.

Example:
    $ embodichain dataset info outputs/datasets/arm7_table_push_the_cube_000
    $ embodichain dataset preview outputs/datasets/arm7_table_push_the_cube_000 --episode 0
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any, Optional, Sequence

PROG = "embodichain dataset"
#: How to install the embodichain-viewer plugin, which ``dataset view`` needs.
VIEWER_INSTALL = "pip install -e plugins/embodichain-viewer  (or: pip install embodichain-viewer)"
#: Episodes ``info`` lists without ``--episodes``.
EPISODE_LINES = 20


def build_parser() -> argparse.ArgumentParser:
    """The ``dataset`` parser with its ``info`` and ``preview`` subcommands."""
    parser = argparse.ArgumentParser(prog=PROG, description="Inspect LeRobot datasets recorded by embodichain.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    info = sub.add_parser("info", help="episodes, frames, features, fps and tasks of a dataset")
    info.add_argument("path", metavar="PATH", help="dataset folder (holds meta/info.json)")
    info.add_argument("--json", action="store_true", help="print the summary as JSON")
    info.add_argument(
        "--episodes",
        action="store_true",
        help="list every episode (default: the first 20): length, success, env id, episode seed",
    )
    prev = sub.add_parser("preview", help="camera contact sheet (or mp4) and state/action plot of an episode")
    prev.add_argument("path", metavar="PATH", help="dataset folder (holds meta/info.json)")
    prev.add_argument("--episode", type=int, required=True, metavar="N", help="episode index")
    prev.add_argument(
        "--out", default="dataset_previews", metavar="DIR", help="output folder (default: ./dataset_previews)"
    )
    prev.add_argument(
        "--format",
        choices=("png", "mp4"),
        default="png",
        help="camera preview: a contact-sheet PNG (default) or an mp4 of every frame",
    )
    prev.add_argument("--frames", type=int, default=8, metavar="K", help="frames in the contact sheet (default 8)")
    _add_replay(sub)
    _add_view(sub)
    return parser


def _add_view(sub: Any) -> None:
    view = sub.add_parser("view", help="replay an episode in the viewer, the recorded camera frames beside it")
    try:
        from embodichain_viewer.dataset_view import add_view_arguments
    except ImportError:  # run() prints how to install it
        view.add_argument("rest", nargs=argparse.REMAINDER)
        return
    add_view_arguments(view)


def _add_replay(sub: Any) -> None:
    from embodichain_lerobot.replay import MIN_PSNR

    rep = sub.add_parser("replay", help="replay recorded episodes in the simulator and compare them frame by frame")
    rep.add_argument("path", metavar="PATH", help="dataset folder (holds meta/embodichain_env.json)")
    which = rep.add_mutually_exclusive_group()
    which.add_argument("--episode", type=int, metavar="N", help="replay episode N (default: episode 0)")
    which.add_argument("--all", action="store_true", help="replay every episode")
    rep.add_argument("--json", metavar="FILE", help="write the per-episode, per-feature results as JSON")
    rep.add_argument(
        "--atol", type=float, metavar="X", help="numeric tolerance (default: 0 on mujoco_batch, 1e-3 on warp)"
    )
    rep.add_argument(
        "--min_psnr", type=float, default=MIN_PSNR, metavar="DB", help=f"colour frames' PSNR floor (default {MIN_PSNR})"
    )
    rep.add_argument(
        "--image_frames", type=int, default=3, metavar="K", help="camera frames compared per episode (default 3)"
    )


def _view(args: argparse.Namespace) -> int:
    """``dataset view`` lives in the embodichain-viewer plugin; without it, how to install it."""
    try:
        from embodichain_viewer.dataset_view import run_view
    except ImportError:
        print(f"{PROG} view: needs the embodichain-viewer plugin; install it with: {VIEWER_INSTALL}", file=sys.stderr)
        return 2
    return run_view(args)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``embodichain dataset`` with ``argv``; return the exit code."""
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    from embodichain_lerobot.reading import go_offline

    go_offline()
    try:
        if args.command == "info":
            return _info(args)
        if args.command == "replay":
            from embodichain_lerobot.replay_cli import run_replay

            return run_replay(args)
        if args.command == "view":
            return _view(args)
        return _preview(args)
    except BrokenPipeError:  # the output was piped into `head` or similar
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except FileNotFoundError as err:
        print(f"{PROG}: {err}", file=sys.stderr)
        return 2
    except (IndexError, ValueError) as err:
        print(f"{PROG} {args.command}: {err}", file=sys.stderr)
        return 2
    except Exception as err:  # a broken dataset: say what failed, no traceback
        print(f"{PROG} {args.command}: failed: {err!r}", file=sys.stderr)
        return 1


def _info(args: argparse.Namespace) -> int:
    from embodichain_lerobot.reading import dataset_summary, format_episodes, format_summary, read_sidecar

    summary = dataset_summary(args.path)
    if args.json:
        if args.episodes:
            summary["episode_records"] = read_sidecar(Path(summary["path"]), summary["episodes"])
        print(json.dumps(summary, indent=2))
    else:
        limit = None if args.episodes else EPISODE_LINES
        print(format_summary(summary) + "\n" + format_episodes(summary, limit))
    return 0


def _preview(args: argparse.Namespace) -> int:
    from embodichain_lerobot.preview import preview_episode
    from embodichain_lerobot.reading import check_dataset_dir

    check_dataset_dir(args.path)
    if args.frames < 1:
        raise ValueError(f"--frames must be >= 1, got {args.frames}")
    for path in preview_episode(args.path, args.episode, args.out, args.format, args.frames):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
