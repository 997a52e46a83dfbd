"""Video encoding spread over several processes (``params.encoder_processes`` above 1).

With streamed videos (``use_videos`` and ``streaming_encoding``) and a dataset writer
process, the recording process sends each env's camera frames straight to the encoder
process that serves the env (env ``e`` to process ``e % N``: envs are alike, so this
spreads the work evenly), while ONE dataset writer process
(:mod:`embodichain_lerobot.writer_process`) keeps writing the dataset: it gets each
committed episode without its videos, waits for the encoder process to finish them
(:mod:`embodichain_lerobot.encoder_files`), and saves and publishes the episode exactly as
before (crash-safe, in commit order). Frames travel once, from the recording process to
their encoder process.

Each :class:`EncoderProcess` is a :class:`~embodichain_lerobot.writer_process.WriterProcess`
(the same launch, message queue, sender and receiver threads) running
:mod:`embodichain_lerobot.encoder_child`. A committed episode's ``finish`` message leaves
for its encoder process before the episode leaves for the dataset writer (the writer's
sender waits for it), so after a ``SIGKILL`` of the recording process every episode the
dataset writer holds has its frames and its finish in its encoder process, which finishes
them before it exits; the writer then saves them all.
"""

from __future__ import annotations

import itertools
import threading
from pathlib import Path
from typing import Any, Iterable, Optional

from embodichain_lerobot.encoder_files import ENCODING
from embodichain_lerobot.writer_process import _REPLY_TIMEOUT_S, WriterProcess


class EncoderProcess(WriterProcess):
    """One encoder process: a :class:`WriterProcess` running :mod:`embodichain_lerobot.encoder_child`."""

    child_module = "embodichain_lerobot.encoder_child"
    child_role = "video encoder process"
    avoid_hint = "set the recorder's params.encoder_processes to 1 to encode in the dataset writer process"

    def death_message(self) -> str:
        """What happened (the episodes it had not finished fail in the dataset writer, by name)."""
        return (
            f"a video encoder process exited (code {self.exit_code}; its own error, if any, is on stderr above); "
            "the episodes whose videos it had not finished are not saved"
        )

    def finalize(self) -> Optional[Path]:
        """Let the child finish every message before (committed episodes' videos), then stop it."""
        if self._finalized:
            return None
        self._finalized = True
        if self._proc is None:
            return None
        try:
            self.submit("finalize", None).result(_REPLY_TIMEOUT_S)
        except Exception:  # a dead encoder: the dataset writer reports each episode it did not finish
            pass
        finally:
            self._stop()
        return None


class EncoderPool:
    """``count`` encoder processes; env ``e``'s videos are encoded by process ``e % count``.

    Example:
        >>> pool = EncoderPool(2)
        >>> pool.index_of(0), pool.index_of(3)
        (0, 1)
    """

    def __init__(self, count: int):
        if count < 1:
            raise ValueError(f"an encoder pool needs at least 1 process, got {count}")
        self.processes = [EncoderProcess() for _ in range(count)]
        self._tickets = itertools.count()
        self.folder: Optional[Path] = None

    def index_of(self, env_id: int) -> int:
        """The process that encodes env ``env_id``'s videos."""
        return int(env_id) % len(self.processes)

    def start(self) -> None:
        """Launch the processes (idempotent; they import lerobot while the first episodes run)."""
        for proc in self.processes:
            proc.start()

    def open(
        self,
        root: Path,
        fps: int,
        vcodec: str,
        encoder_threads: Optional[int],
        streamed: Iterable[str],
        lossless: Iterable[str],
    ) -> dict[str, Any]:
        """Tell every process the dataset's video settings; returns what the dataset writer
        process needs to find the finished videos (``WriterProcess.open``'s ``remote``)."""
        self.folder = Path(root) / ENCODING
        keys = sorted(streamed)
        settings = (str(self.folder), int(fps), vcodec, encoder_threads, keys, sorted(lossless))
        for proc in self.processes:
            proc.start()
            proc.root, proc.streamed = Path(root), frozenset(keys)
            proc.post("open", settings)
        return {"folder": str(self.folder), "pids": [proc.pid for proc in self.processes]}

    def _groups(self, env_ids: Iterable[int]) -> dict[int, list[int]]:
        groups: dict[int, list[int]] = {}
        for env_id in env_ids:
            groups.setdefault(self.index_of(env_id), []).append(int(env_id))
        return groups

    def stream_frames(self, snapshot: dict, env_ids: list[int]) -> None:
        """Send frame t of the live episodes of ``env_ids`` (rows of ``snapshot``), each env's to its process."""
        for index, ids in self._groups(env_ids).items():  # a snapshot's rows are env ids
            self.processes[index].stream_frames(snapshot, ids)

    def restart(self, env_ids: list[int]) -> None:
        """The live episodes of ``env_ids`` end without a commit: their encoding is cancelled."""
        for index, ids in self._groups(env_ids).items():
            self.processes[index].restart(ids)

    def finish(self, env_id: int) -> tuple[tuple[str, int], threading.Event]:
        """Ask env ``env_id``'s process to finish its committed episode's videos.

        Returns:
            The ticket the dataset writer waits for (its name and the encoder's pid), and an
            event set once the request has left (``WriterProcess.submit_episode``'s ``after``).
        """
        proc = self.processes[self.index_of(env_id)]
        name, sent = f"env{int(env_id)}_{next(self._tickets)}", threading.Event()
        proc.post("finish", (int(env_id), name), on_sent=sent)
        return (name, int(proc.pid or 0)), sent

    def finalize(self) -> None:
        """Stop every process once it has handled everything sent before (idempotent)."""
        for proc in self.processes:
            proc.finalize()


def pool_for(params: Any, num_envs: int) -> Optional[EncoderPool]:
    """The encoder pool that ``params.encoder_processes`` asks for (``None``: the dataset writer
    process encodes, as with 1).

    ``params`` are the recorder's resolved :class:`~embodichain_lerobot.config.RecorderParams`
    (``writer_process`` decided). An explicit count above 1 needs streamed videos and a writer
    process; ``"auto"`` quietly means 1 without them.

    Raises:
        ConfigError: an explicit count above 1 where videos are not streamed to a writer process.
    """
    from embodichain_core.config.errors import ConfigError

    from embodichain_lerobot.config import encoder_process_count

    setting = params.encoder_processes
    streamed = params.use_videos and params.streaming_encoding and params.writer_process
    if not streamed:
        if setting != "auto" and setting > 1:
            raise ConfigError(
                "params.encoder_processes",
                f"{setting} encoder processes encode streamed videos, which needs use_videos: true, "
                "streaming_encoding: true and writer_process: true (AsyncLeRobotRecorder's default); "
                f"got use_videos {params.use_videos}, streaming_encoding {params.streaming_encoding}, "
                f"writer_process {params.writer_process}. Set them, or leave encoder_processes out",
            )
        return None
    count = encoder_process_count(setting, num_envs)
    return EncoderPool(count) if count > 1 else None
