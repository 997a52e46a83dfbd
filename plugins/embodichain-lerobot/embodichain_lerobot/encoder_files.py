"""How finished videos pass from the encoder processes to the dataset writer process.

With ``params.encoder_processes`` above 1 (:mod:`embodichain_lerobot.encoder_pool`), each
encoder process encodes the streamed videos of its envs into temporary mp4 files under
``<dataset>/.embodichain_encoding/`` (beside the writer's staging folder; loaders never
look there). When an episode is committed, the recording process names it with a
*ticket*; the encoder process finishes that env's videos and writes the ticket's result
file (``<ticket>.result``: the pickled ``("ok", {video_key: (mp4 path, stats)})`` or
``("error", exception)``, replaced atomically), and the dataset writer, which got the
episode under the same ticket, waits for that file and saves the episode with those videos
(:class:`FinishedVideos` stands in for lerobot's streaming encoder in ``save_episode``).

A writer that waits for a ticket whose encoder process is gone (it crashed, or was killed)
gets an error for that episode instead of waiting forever (:func:`wait_result`).
"""

from __future__ import annotations

import os
import pickle
import shutil
import time
from pathlib import Path
from typing import Any, Iterable, Optional

#: The folder of the encoder processes' temporary videos and result files, inside the dataset.
ENCODING = ".embodichain_encoding"
_POLL_S = 0.005


def result_path(folder: Path, ticket: str) -> Path:
    """The result file of ``ticket``."""
    return Path(folder) / f"{ticket}.result"


def write_result(folder: Path, ticket: str, status: str, value: Any) -> None:
    """Publish the result of ``ticket`` (``status`` ``"ok"`` or ``"error"``) atomically."""
    dest = result_path(folder, ticket)
    tmp = dest.with_name(f".{dest.name}.tmp")
    dest.parent.mkdir(exist_ok=True)  # inside the dataset folder, which must exist
    tmp.write_bytes(pickle.dumps((status, value)))
    os.replace(tmp, dest)


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, exited but not reaped yet, counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        return state not in ("Z", "X")
    except (OSError, IndexError):
        if Path("/proc/self").exists():  # Linux: no such process
            return False
    try:  # no /proc (macOS): a signal 0 asks
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def wait_result(folder: Path, ticket: str, pid: int, timeout: float = 3600.0) -> dict[str, tuple[Path, Optional[dict]]]:
    """The finished videos of ``ticket`` (``{video_key: (mp4 path, stats or None)}``) once
    encoder process ``pid`` has written them; the result file is removed.

    Raises:
        RuntimeError: the encoder process exited without finishing them, or ``timeout`` passed.
        Exception: the encoder process's own error for this episode.
    """
    path, deadline, polls = result_path(folder, ticket), time.monotonic() + timeout, 0
    while not path.exists():
        polls += 1
        if polls % 20 == 0 and not alive(pid) and not path.exists():  # every ~0.1 s: /proc reads cost
            raise RuntimeError(
                f"the video encoder process (pid {pid}) exited before it finished the videos of episode "
                f"{ticket!r}; the episode is not saved (the encoder's own error, if any, is on stderr above)"
            )
        if time.monotonic() > deadline:
            raise RuntimeError(f"the videos of episode {ticket!r} were not finished within {timeout:.0f} s")
        time.sleep(_POLL_S)
    status, value = pickle.loads(path.read_bytes())
    path.unlink()
    if status == "error":
        raise value
    return {key: (Path(mp4), stats) for key, (mp4, stats) in value.items()}


def wait_exit(pids: Iterable[int], timeout: float = 120.0) -> None:
    """Wait (at most ``timeout`` seconds) until the processes ``pids`` have exited."""
    deadline = time.monotonic() + timeout
    while any(alive(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.02)


def remove_encoding_folder(root: Path) -> None:
    """Remove ``<root>/.embodichain_encoding`` (temporary videos of unsaved episodes)."""
    shutil.rmtree(Path(root) / ENCODING, ignore_errors=True)


class FinishedVideos:
    """lerobot's streaming-encoder interface over videos that are already finished: within
    ``prefed_encoder``, ``save_episode`` takes them as its encoder's results."""

    def __init__(self, results: dict[str, tuple[Path, Optional[dict]]]):
        self._results = results

    def start_episode(self, video_keys: Any, temp_dir: Any) -> None:
        """Encoded elsewhere."""

    def feed_frame(self, video_key: str, image: Any) -> None:
        """Encoded elsewhere."""

    def finish_episode(self) -> dict[str, tuple[Path, Optional[dict]]]:
        """The finished videos."""
        return self._results

    def cancel_episode(self) -> None:
        """Remove the finished videos (the episode is not saved)."""
        for mp4, _ in self._results.values():
            shutil.rmtree(Path(mp4).parent, ignore_errors=True)

    def close(self) -> None:
        """Nothing is held open."""
