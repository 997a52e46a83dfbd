"""``embodichain dataset view PATH --episode N``: a recorded episode replayed in the viewer.

The env is rebuilt from the dataset's ``meta/embodichain_env.json`` and the episode
re-simulated from its recorded seed and actions by embodichain-lerobot's
:class:`~embodichain_lerobot.replay.Replayer` (which also compares every frame with the
recording); the viewer shows the re-simulated scene, with the recorded camera frames
(``recorded/<feature>``) beside the re-rendered ones. The replay runs at real time
(``--speed``); the comparison is printed as soon as it ends, and the viewer stays open
afterwards until Ctrl-C, SIGTERM or the window closes (each says goodbye), unless ``--exit``.
"""

from __future__ import annotations

import argparse
import signal
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from embodichain_viewer.state import image_rgb

__all__ = ["add_view_arguments", "run_view", "view_episode"]


def add_view_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags of ``embodichain dataset view``."""
    parser.add_argument("path", metavar="PATH", help="dataset folder (holds meta/embodichain_env.json)")
    parser.add_argument("--episode", type=int, default=0, metavar="N", help="episode to view (default 0)")
    parser.add_argument(
        "--viewer",
        choices=("auto", "native", "browser"),
        default="auto",
        help="auto (default): a native window with a display, else a browser page on localhost",
    )
    parser.add_argument("--port", type=int, default=8080, help="first localhost port of the browser viewer")
    parser.add_argument("--speed", type=float, default=1.0, help="multiple of real time (default 1; 0: max)")
    parser.add_argument("--exit", action="store_true", help="close the viewer when the episode has been replayed")


class Terminated(Exception):
    """SIGTERM arrived (raised in the main thread by :func:`run_view`'s handler)."""


def _on_sigterm(signum: int, frame: Any) -> None:
    raise Terminated()


def run_view(args: argparse.Namespace) -> int:
    """Run ``embodichain dataset view``: the comparison is printed as soon as the episode has
    been replayed (the viewer may stay open after it); 0 when it matched the recording, 1
    when not, 130 after Ctrl-C and 143 after SIGTERM during the replay (each says goodbye)."""
    from embodichain_lerobot.replay_cli import format_replay

    outcome: list[Any] = []

    def report(result: Any, replayer: Any) -> None:
        outcome.append(result)
        print(format_replay(result, replayer.atol, replayer.min_psnr), flush=True)

    main = threading.current_thread() is threading.main_thread()  # handlers live in the main thread
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if main else None
    try:
        view_episode(args.path, args.episode, args.viewer, args.port, args.speed, not args.exit, on_replayed=report)
    except (KeyboardInterrupt, Terminated) as stop:
        return _goodbye(stop, outcome)
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return 0 if outcome and outcome[0].ok else 1


def _goodbye(stop: BaseException, outcome: list[Any]) -> int:
    """Say why the viewer closed and what was compared; the exit status: 143 after SIGTERM,
    else the comparison's (0 or 1), or 130 when Ctrl-C came before it."""
    what = "SIGTERM" if isinstance(stop, Terminated) else "Ctrl-C"
    if outcome:
        print(f"dataset view: {what}: the viewer is closed (the comparison is above)", flush=True)
        return 143 if isinstance(stop, Terminated) else (0 if outcome[0].ok else 1)
    print(f"dataset view: {what} during the replay: the viewer is closed, nothing was compared", flush=True)
    return 143 if isinstance(stop, Terminated) else 130


def view_episode(
    path: str | Path,
    episode: int,
    viewer: str = "auto",
    port: int = 8080,
    speed: float = 1.0,
    hold: bool = True,
    on_open: Optional[Callable[[Any], None]] = None,
    on_replayed: Optional[Callable[[Any, Any], None]] = None,
) -> tuple[Any, Any]:
    """Replay ``episode`` of the dataset at ``path`` with the viewer open.

    Args:
        path: the dataset folder.
        episode: the episode index.
        viewer: ``"auto"``, ``"native"`` or ``"browser"``.
        port: first localhost port of the browser viewer.
        speed: multiple of real time (``0``: as fast as it goes).
        hold: keep the viewer open after the replay until Ctrl-C or its window closes.
        on_open: called with the viewer session once it is open (tests).
        on_replayed: called with ``(EpisodeReplay, Replayer)`` as soon as the episode has been
            replayed, before the viewer is held open.

    Returns:
        ``(EpisodeReplay, Replayer)``: the frame-by-frame comparison and its tolerances.

    Raises:
        IndexError: no such episode. ValueError: the episode cannot be replayed.
    """
    from embodichain_core.viewing import force_viewer
    from embodichain_lerobot.episode_reader import EpisodeFiles
    from embodichain_lerobot.replay import Replayer

    files = EpisodeFiles(path, episode)
    frames = recorded_frames(files)
    replayer = Replayer(files.root)
    try:
        with force_viewer(viewer):
            session = replayer.env.unwrapped._viewer
        session.controls.speed = speed if speed > 0 else None
        start = session.steps
        session.extra_images = lambda: {
            name: seq[min(session.steps - start, len(seq) - 1)] for name, seq in frames.items() if seq
        }
        if on_open is not None:
            on_open(session)
        result = replayer.replay(episode, episode_seed(files.root, episode, int(files.info["total_episodes"])))
        if on_replayed is not None:
            on_replayed(result, replayer)
        if hold:
            _hold(session)
    finally:
        replayer.close()
    return result, replayer


def recorded_frames(files: Any) -> dict[str, list[np.ndarray]]:
    """``"recorded/<feature>"`` -> every frame of the episode's camera features, as RGB."""
    out: dict[str, list[np.ndarray]] = {}
    for name, ft in files.features.items():
        if ft.get("dtype") in ("video", "image"):
            images = [image_rgb(f) for f in files.camera_frames(name, range(files.length))]
            out[f"recorded/{name.removeprefix('observation.images.')}"] = [i for i in images if i is not None]
    return out


def episode_seed(root: Path, episode: int, total: int) -> Optional[int]:
    """The recorded ``episode_seed`` of ``episode`` (``None`` when it has none)."""
    from embodichain_lerobot.reading import read_sidecar

    for position, record in enumerate(read_sidecar(root, total)):
        if int(record.get("lerobot_episode_index", position)) == episode:
            seed = record.get("episode_seed")
            return None if seed is None else int(seed)
    return None


def _hold(session: Any) -> None:
    """Keep the viewer open until its window closes (Ctrl-C and SIGTERM reach the caller)."""
    print("episode replayed; the viewer stays open (Ctrl-C to close)", flush=True)
    while session.viewer.alive():
        time.sleep(0.2)
