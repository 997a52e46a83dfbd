"""The child side of :mod:`embodichain_lerobot.writer_process`: ``python -m embodichain_lerobot.writer_child FD``.

It imports lerobot at once (seconds, while the first episodes run), then answers the
recording process's messages in order:

* ``open``: create the :class:`~embodichain_lerobot.writer.DatasetWriter`;
* ``frames``: video frames of the live episodes (colour; depth and masks when they are
  lossless videos), fed to one :class:`~embodichain_lerobot.lossless_video.RoutedEncoder`
  per env (lerobot's ``StreamingVideoEncoder`` for colour; started at an episode's first
  frame), so a video is encoded while its episode runs;
* ``restart``: those envs' live episodes end without a commit (their encoding is cancelled);
* ``episode``: write a committed episode; with streamed videos, lerobot's ``save_episode``
  finishes that env's encoder instead of its own (:func:`prefed_encoder`), or, when encoder
  processes encode them (``params.encoder_processes``, :mod:`embodichain_lerobot.encoder_pool`),
  takes the videos they finished under the episode's ticket;
* ``finalize``: cancel the live encoders, finalize the dataset, exit.

``open``, ``episode`` and ``finalize`` get one reply each, ``("ok", value)`` or
``("error", exception)``. The child reads its socket on a thread from its first moment
(:class:`Inbox`: the recording process never waits for lerobot's import), runs at a lower
priority (:data:`~embodichain_lerobot.child_io.NICENESS`), and ignores ``SIGINT`` and ``SIGTERM`` (a Ctrl-C in the
terminal, or a ``kill`` of the process group, reaches it too; the recording process
decides what happens). When the recording process dies (even by ``SIGKILL``), the child
sees the socket close, writes every episode and frame message it had already received
(in order, as if the recording process lived), then finalizes the dataset: an episode
that left the recording process is never dropped. Its last line says how many episodes the
dataset holds (its ``meta/info.json``); it prints nothing once the shell has taken the
terminal back (the prompt is shown: the dataset on disk tells the rest).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import time
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Iterator, Optional

import numpy as np

from embodichain_lerobot.encoder_files import FinishedVideos, wait_exit, wait_result
from embodichain_lerobot.child_io import Inbox, _picklable, _say, run_child, start_child
from embodichain_lerobot.writer_process import WriterProcessError, from_columns


#: Frames queued in the encoders (all envs and cameras) above which the child stops reading.
MAX_ENCODER_BACKLOG = 512
#: Tests only: a file holding a number ``N``; the child starts its episode ``i`` only once the
#: file exists and ``i < N`` (it polls; a held episode is announced in ``<file>.held``), so a
#: test decides exactly how many episodes the child has written when it kills a process.
#: Unset (the default): no effect.
TEST_GATE_ENV = "EMBODICHAIN_WRITER_TEST_GATE"


class _Prefed:
    """lerobot's streaming-encoder interface over an encoder that already has the episode's
    frames: ``add_frame`` neither starts it nor feeds it again; ``save_episode`` finishes it."""

    def __init__(self, encoder: Any):
        self._encoder = encoder

    def start_episode(self, video_keys: Any, temp_dir: Any) -> None:
        """Already started at the episode's first streamed frame."""

    def feed_frame(self, video_key: str, image: Any) -> None:
        """Already fed while the episode ran."""

    def finish_episode(self) -> Any:
        return self._encoder.finish_episode()

    def cancel_episode(self) -> None:
        self._encoder.cancel_episode()

    def close(self) -> None:
        self._encoder.close()


@contextlib.contextmanager
def prefed_encoder(dataset: Any, encoder: Any) -> Iterator[None]:
    """Within the block, ``dataset`` saves its episode's videos from ``encoder`` (lerobot's
    ``LeRobotDataset._streaming_encoder`` is swapped; documented in docs/datasets.md)."""
    saved = dataset._streaming_encoder
    dataset._streaming_encoder = _Prefed(encoder)
    try:
        yield
    finally:
        dataset._streaming_encoder = saved


def _rgb(frames: np.ndarray) -> np.ndarray:
    """RGB frames of RGBA ones (the recorder sends them with their alpha); torch's strided copy
    is about 4 times numpy's (torch is imported here anyway, by lerobot)."""
    if frames.shape[-1] != 4:
        return frames
    import torch

    return torch.from_numpy(frames)[..., :3].contiguous().numpy()


class ChildWriter:
    """The state of the child: the dataset writer and one video encoder per env."""

    def __init__(self) -> None:
        self.writer: Any = None
        self.open_error: Optional[BaseException] = None
        self.streamed: list[str] = []
        self.encoders: dict[int, Any] = {}
        self.live: set[int] = set()  # envs whose encoder has an episode running
        self.remote: Optional[dict] = None  # the encoder processes' folder and pids, when they encode

    def handle(self, command: str, payload: Any) -> Any:
        """Carry out one message; its reply value."""
        if command == "open":
            return self._open(*payload)
        if command == "finalize":
            return self.finalize()
        if self.writer is None:
            if command in ("frames", "restart"):
                return None  # the open failed: its error is the reply to the next episode
            if self.open_error is not None:
                raise self.open_error
            raise WriterProcessError(f"{command!r} before the dataset was opened")
        if command == "frames":
            return self._frames(*payload)
        if command == "restart":
            for env_id in set(payload) & self.live:
                self.live.discard(env_id)
                self.encoders[env_id].cancel_episode()
            return None
        if command == "episode":
            return self._episode(*payload)
        raise WriterProcessError(f"unknown command {command!r}")

    def _open(self, root: str, args: tuple, kwargs: dict, streamed: list[str], remote: Optional[dict] = None) -> None:
        from embodichain_lerobot.writer import DatasetWriter

        try:
            self.writer = DatasetWriter(Path(root), *args, **kwargs)
        except BaseException as err:
            self.open_error = err
            shutil.rmtree(root, ignore_errors=True)  # the recorder reserved it; nothing was saved
            raise
        self.streamed, self.remote = list(streamed), remote

    def _encoder(self, env_id: int) -> Any:
        if env_id not in self.encoders:  # a RoutedEncoder like the dataset's (lerobot's for colour)
            self.encoders[env_id] = self.writer.dataset._streaming_encoder.fresh()
        return self.encoders[env_id]

    def _frames(self, arrays: dict[str, np.ndarray], env_ids: list[int]) -> None:
        self._wait_for_encoders()
        rgb = {key: _rgb(arrays[key]) for key in self.streamed}
        for row, env_id in enumerate(env_ids):
            encoder = self._encoder(env_id)
            if env_id not in self.live:
                encoder.start_episode(video_keys=self.streamed, temp_dir=self.writer.dataset.root)
                self.live.add(env_id)
            for key in self.streamed:
                encoder.feed_frame(key, rgb[key][row])

    def _wait_for_encoders(self) -> None:
        """Hold new frames while the encoders have :data:`MAX_ENCODER_BACKLOG` frames queued (the
        recording process then waits too, see ``writer_process.MAX_QUEUED_MESSAGES``)."""
        while self._backlog() > MAX_ENCODER_BACKLOG:
            time.sleep(0.005)

    def _backlog(self) -> int:
        return sum(enc.backlog() for env_id, enc in self.encoders.items() if env_id in self.live)

    def _episode(
        self,
        env_id: int,
        columns: dict,
        length: int,
        record: dict,
        subtasks: list[str],
        ticket: Optional[tuple[str, int]] = None,
    ) -> int:
        _test_gate(self.writer.num_episodes, self.writer.root)
        for name in subtasks:  # the same indices as the recording process gave
            self.writer.subtask_index(name)
        if not self.streamed:
            return int(self.writer.write_episode(from_columns(columns, length), record))
        features = self.writer.dataset.features
        dummies = {k: np.broadcast_to(np.zeros((), np.uint8), tuple(features[k]["shape"])) for k in self.streamed}
        if ticket is not None and self.remote is not None:  # finished by an encoder process
            videos = FinishedVideos(wait_result(Path(self.remote["folder"]), *ticket))
            with prefed_encoder(self.writer.dataset, videos):
                return int(self.writer.write_episode(from_columns(columns, length, dummies), record))
        self.live.discard(env_id)  # the save finishes its encoder (or cancels it on an error)
        with prefed_encoder(self.writer.dataset, self._encoder(env_id)):
            return int(self.writer.write_episode(from_columns(columns, length, dummies), record))

    def finalize(self) -> Optional[str]:
        for env_id in self.live:
            self.encoders[env_id].cancel_episode()
        self.live.clear()
        if self.remote is not None:  # their temporary videos go with the dataset's staging
            wait_exit(self.remote["pids"])
        path = self.writer.finalize() if self.writer is not None else None
        return str(path) if path is not None else None


def _test_gate(index: int, root: Path) -> None:
    """Wait while the test gate (:data:`TEST_GATE_ENV`) holds episode ``index`` back; a held
    episode is announced with the line ``<root> <index>`` in ``<gate>.held``."""
    gate = os.environ.get(TEST_GATE_ENV)
    announced = False
    while gate:
        try:
            if index < int(Path(gate).read_text().strip() or 0):
                return
        except (OSError, ValueError):
            pass
        if not announced:
            with open(f"{gate}.held", "a") as held:
                held.write(f"{root} {index}\n")
            announced = True
        time.sleep(0.02)


def _orphaned(state: ChildWriter, inbox: "Inbox") -> None:
    """The recording process is gone: write every message already received (episodes, their
    streamed frames), then finalize. Every episode that left the recording process is saved,
    exactly as if it had lived; nothing is half-written. The farewell line states the episodes
    that ``meta/info.json`` counts (what loads), not just the ones written after the parent died."""
    written = 0
    while True:
        try:
            command, payload = inbox.get()
        except (EOFError, OSError):
            break
        if command == "finalize":
            break
        try:
            value = state.handle(command, payload)
        except BaseException as err:  # the episodes published before stay intact
            _say(f"embodichain writer process: {command} failed after the recording process died: {err!r}")
            if command == "episode":
                break  # a broken writer accepts nothing more
            continue
        written += command == "episode" and int(value) >= 0
    root = state.writer.root if state.writer is not None else None
    try:
        state.finalize()
    except Exception:  # its published episodes are intact either way
        pass
    if root is not None:
        from embodichain_lerobot.folders import folder_status

        _say(
            f"embodichain writer process: the recording process is gone; {folder_status(root).episodes} "
            f"episode(s) are saved in {root} ({written} of them written after it died), finalized"
        )


def serve(conn: Connection, inbox: Optional[Inbox] = None) -> None:
    """Answer the recording process's messages until ``finalize`` or until it goes away."""
    state, inbox = ChildWriter(), inbox or Inbox(conn)
    while True:
        try:
            command, payload = inbox.get()
        except (EOFError, OSError):
            return _orphaned(state, inbox)
        try:
            reply: tuple[str, Any] = ("ok", state.handle(command, payload))
        except BaseException as err:
            reply = ("error", _picklable(err))
        if command in ("frames", "restart"):
            if reply[0] == "error":  # no reply is expected: the episode's save reports it
                print(f"embodichain writer process: {command} failed: {reply[1]!r}", file=sys.stderr)
            continue
        try:
            conn.send(reply)
        except OSError:  # it died while this command ran: the rest of the inbox is still written
            return _orphaned(state, inbox)
        if command == "finalize" and reply[0] == "ok":
            return


def main(argv: Optional[list[str]] = None) -> None:
    """Entry point of the child."""
    conn, inbox = start_child(argv)
    import lerobot.datasets.lerobot_dataset  # noqa: F401  (seconds: now, before the first episode arrives)

    run_child(serve, conn, inbox)


if __name__ == "__main__":
    main()
