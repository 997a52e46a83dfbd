"""An encoder process of :mod:`embodichain_lerobot.encoder_pool`: ``python -m embodichain_lerobot.encoder_child FD``.

It encodes the streamed videos of the envs the recording process assigns to it, with one
:class:`~embodichain_lerobot.lossless_video.RoutedEncoder` per env (lerobot's
``StreamingVideoEncoder`` for colour, with the settings lerobot's ``LeRobotDataset.create``
gives it; lossless H.264 for depth and masks), and answers the recording process's
messages in order:

* ``open``: the encoding folder, fps, codec (``"auto"`` resolved here as in the dataset
  writer), encoder threads, the streamed video keys and the lossless ones;
* ``frames``: frame t of the live episodes of some of its envs (started at an episode's first frame);
* ``restart``: those envs' live episodes end without a commit: their encoding is cancelled
  and their temporary videos removed;
* ``finish``: an env's episode is committed: its videos are finished and published under
  the episode's ticket (:func:`~embodichain_lerobot.encoder_files.write_result`), where
  the dataset writer process picks them up;
* ``finalize``: cancel the live episodes, reply, exit.

Like the dataset writer process it reads its socket on a thread from its first moment,
runs at a lower priority and ignores ``SIGINT``/``SIGTERM``; when the recording process
dies it still handles every message it had received (so every committed episode's videos
are finished), then cancels the live episodes and exits.
"""

from __future__ import annotations

import time
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Optional

import numpy as np

from embodichain_lerobot.encoder_files import write_result
from embodichain_lerobot.child_io import Inbox, _picklable, _say, run_child, start_child
from embodichain_lerobot.writer_child import MAX_ENCODER_BACKLOG, _rgb


class EncoderChild:
    """The state of an encoder process: one video encoder per env it serves."""

    def __init__(self) -> None:
        self.folder: Optional[Path] = None
        self.open_error: Optional[BaseException] = None
        self.streamed: list[str] = []
        self.template: Any = None  # a RoutedEncoder with the dataset's settings; each env gets a fresh one
        self.encoders: dict[int, Any] = {}
        self.live: set[int] = set()  # envs whose encoder has an episode running

    def handle(self, command: str, payload: Any) -> Any:
        """Carry out one message; its reply value (only ``finalize`` is answered)."""
        if command == "open":
            return self._open(*payload)
        if command == "finalize":
            return self.finalize()
        if command == "finish":
            return self._finish(*payload)
        if self.template is None:
            return None  # the open failed: the finish of each episode reports it
        if command == "frames":
            return self._frames(*payload)
        if command == "restart":
            for env_id in set(payload) & self.live:
                self.live.discard(env_id)
                self.encoders[env_id].cancel_episode()
            return None
        raise ValueError(f"unknown command {command!r}")

    def _open(
        self, folder: str, fps: int, vcodec: str, threads: Optional[int], streamed: list[str], lossless: list[str]
    ) -> None:
        from lerobot.datasets.video_utils import StreamingVideoEncoder

        from embodichain_lerobot.encoding import resolve_vcodec
        from embodichain_lerobot.lossless_video import RoutedEncoder

        self.folder, self.streamed = Path(folder), list(streamed)
        try:  # pix_fmt, g, crf and preset: lerobot's defaults, as LeRobotDataset.create passes them
            colour = StreamingVideoEncoder(
                fps=fps, vcodec=resolve_vcodec(vcodec), queue_maxsize=0, encoder_threads=threads
            )
            self.template = RoutedEncoder(colour, lossless)
        except BaseException as err:
            self.open_error = err

    def _encoder(self, env_id: int) -> Any:
        if env_id not in self.encoders:
            self.encoders[env_id] = self.template.fresh()
        return self.encoders[env_id]

    def _frames(self, arrays: dict[str, np.ndarray], env_ids: list[int]) -> None:
        if not self._dataset_exists():
            return
        while self._backlog() > MAX_ENCODER_BACKLOG:  # the recording process then waits too
            time.sleep(0.005)
        rgb = {key: _rgb(arrays[key]) for key in self.streamed}
        for row, env_id in enumerate(env_ids):
            encoder = self._encoder(env_id)
            if env_id not in self.live:
                self.folder.mkdir(exist_ok=True)  # type: ignore[union-attr]
                encoder.start_episode(video_keys=self.streamed, temp_dir=self.folder)
                self.live.add(env_id)
            for key in self.streamed:
                encoder.feed_frame(key, rgb[key][row])

    def _dataset_exists(self) -> bool:
        """Whether the dataset folder is there (the dataset writer removes it when it cannot
        create the dataset; that error reaches the recording with the first episode)."""
        return self.folder is not None and self.folder.parent.is_dir()

    def _backlog(self) -> int:
        return sum(enc.backlog() for env_id, enc in self.encoders.items() if env_id in self.live)

    def _finish(self, env_id: int, ticket: str) -> None:
        """Finish env ``env_id``'s videos and publish them (or the error) under ``ticket``."""
        if self.folder is None:
            raise ValueError("'finish' before 'open'")
        if not self._dataset_exists():  # nobody waits for it: the dataset writer has no dataset
            return
        try:
            if self.open_error is not None:
                raise self.open_error
            if env_id not in self.live:
                raise RuntimeError(f"no video frame of env {env_id}'s episode reached its encoder process")
            self.live.discard(env_id)
            results = self.encoders[env_id].finish_episode()
        except BaseException as err:
            write_result(self.folder, ticket, "error", _picklable(err))
            return
        write_result(self.folder, ticket, "ok", {key: (str(mp4), stats) for key, (mp4, stats) in results.items()})

    def finalize(self) -> None:
        """Cancel the live episodes (their temporary videos go)."""
        for env_id in sorted(self.live):
            self.encoders[env_id].cancel_episode()
        self.live.clear()


def serve(conn: Connection, inbox: Inbox) -> None:
    """Answer the recording process's messages until ``finalize``; when it goes away, every
    message already received is handled first (the inbox gives them all before its end)."""
    state = EncoderChild()
    while True:
        try:
            command, payload = inbox.get()
        except (EOFError, OSError):
            break
        try:
            reply: tuple[str, Any] = ("ok", state.handle(command, payload))
        except BaseException as err:
            reply = ("error", _picklable(err))
            _say(f"embodichain encoder process: {command} failed: {err!r}")
        if command == "finalize":
            try:
                conn.send(reply)
            except OSError:  # the recording process is gone: nothing waits for the reply
                pass
            return
    state.finalize()


def main(argv: Optional[list[str]] = None) -> None:
    """Entry point of the encoder process."""
    conn, inbox = start_child(argv)
    import lerobot.datasets.video_utils  # noqa: F401  (seconds: now, before the first frame arrives)

    run_child(serve, conn, inbox)


if __name__ == "__main__":
    main()
