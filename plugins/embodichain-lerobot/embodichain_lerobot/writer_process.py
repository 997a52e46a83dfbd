"""The dataset writer in a child process (``params.writer_process``).

:class:`WriterProcess` has the interface of
:class:`~embodichain_lerobot.writer.DatasetWriter` (``root``, ``num_episodes``,
``num_frames``, ``subtask_index``, ``write_episode``, ``finalize``) and runs the real
writer in a child Python process (:mod:`embodichain_lerobot.writer_child`): lerobot is
imported there, and its per-frame work (frame checks, video encoding, statistics,
parquet and metadata) runs on the child's interpreter, so it never competes with
stepping and rendering for this process's GIL. The child is started with
``subprocess`` (``python -m embodichain_lerobot.writer_child FD``), not
``multiprocessing``: a spawned ``multiprocessing`` child re-imports the user's main
script, which breaks scripts without an ``if __name__ == "__main__"`` guard.

Messages (pickled, over a socket pair with ``multiprocessing.connection``) leave in the
order they were made, from a sender thread, so the recording loop never waits for the
socket: :meth:`post` sends without a reply (camera frames of the live episodes,
restarts), :meth:`submit` returns a future that the receiver thread completes with the
child's reply (``open``, ``episode``, ``finalize``). With :meth:`stream_frames` the
colour frames go to the child while the episode runs and are encoded there as they
arrive (one lerobot streaming encoder per env); a committed episode then carries only
its other features.
"""

from __future__ import annotations

import collections
import queue
import socket
import subprocess
import sys
import threading
from concurrent.futures import Future
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Iterable, Iterator, Optional

import numpy as np

from embodichain_core.errors import RunError

from embodichain_lerobot.storage import finish_orphaned

_REPLY_TIMEOUT_S = 600.0  # importing lerobot and saving an episode on a loaded machine
#: Messages waiting for the sender thread before :meth:`WriterProcess.post` waits: when the
#: child cannot keep up (it also bounds its encoders' backlog), stepping slows down to its pace
#: instead of the backlog growing without bound.
MAX_QUEUED_MESSAGES = 64
_STOP = object()


class WriterProcessError(RunError):
    """The writer process failed in a way that has no exception of its own (it died, or its error did not pickle).

    A :class:`~embodichain_core.errors.RunError`: ``run-env`` prints its message (which
    says what is saved, what was lost and what to do) without a traceback."""


def to_columns(frames: Iterable[dict], skip: Iterable[str] = ()) -> tuple[dict[str, Any], int]:
    """An episode's frames as one stacked array per feature (a few large arrays pickle much
    faster than thousands of small ones); other values (the task string) as lists.
    Features named in ``skip`` (streamed colour) are left out."""
    frame_list, left_out = list(frames), set(skip)
    columns: dict[str, Any] = {}
    for name in frame_list[0] if frame_list else ():
        if name in left_out:
            continue
        values = [f[name] for f in frame_list]
        columns[name] = np.stack(values) if isinstance(values[0], np.ndarray) else values
    return columns, len(frame_list)


def from_columns(columns: dict[str, Any], length: int, extra: Optional[dict] = None) -> Iterator[dict]:
    """The frames of :func:`to_columns` (plus the constant entries ``extra``), one dict per frame."""
    for t in range(length):
        frame = {name: values[t] for name, values in columns.items()}
        frame.update(extra or {})
        yield frame


def _rows(frames: np.ndarray, env_ids: list[int]) -> np.ndarray:
    """Rows ``env_ids`` of a colour batch; the RGB view of an RGBA buffer (what the recorder
    keeps) is sent whole, alpha included: a plain copy, where dropping the alpha is a slow
    strided gather (the child drops it)."""
    base = frames.base
    if isinstance(base, np.ndarray) and base.shape[:-1] == frames.shape[:-1] and base.shape[-1] == 4:
        return base[env_ids]
    return frames[env_ids]


class WriterProcess:
    """A :class:`~embodichain_lerobot.writer.DatasetWriter` that runs in a child process.

    Example:
        >>> proc = WriterProcess()          # doctest: +SKIP
        >>> proc.start()                    # the child imports lerobot meanwhile  # doctest: +SKIP
        >>> proc.open(root, 30, features, "arm7", True, "h264", 0, 0)  # doctest: +SKIP
        >>> proc.write_episode(frames, {"env_id": 0})  # doctest: +SKIP
        >>> proc.finalize()                 # doctest: +SKIP
    """

    #: The module the child runs (``python -m MODULE FD``).
    child_module = "embodichain_lerobot.writer_child"
    #: What the child is called in errors, and the param that avoids starting it.
    child_role = "dataset writer process"
    avoid_hint = "set the recorder's params.writer_process to false to write the dataset in the recording process"

    def __init__(self) -> None:
        self.root: Path = Path()
        self.num_episodes = 0
        self.num_frames = 0
        self.sent_episodes = 0  # episodes handed to the child (saved or not yet)
        self.lost_episodes: list[int] = []  # env ids of episodes sent to a child that died before saving them
        self.exit_code: Optional[int] = None  # the child's, once it died
        self.saved_at_death = 0  # episodes the dataset held when the child died
        self.dead_reported = False  # the recorder raised the child's death: finalize() does not raise it again
        self.streamed: frozenset[str] = frozenset()  # colour features sent with stream_frames
        self._subtasks: dict[str, int] = {}
        self._proc: Optional[subprocess.Popen] = None
        self._conn: Optional[Connection] = None
        self._outbox: queue.SimpleQueue = queue.SimpleQueue()
        self._room = threading.Semaphore(MAX_QUEUED_MESSAGES)
        self._waiting: collections.deque[Future] = collections.deque()
        self._lock = threading.Lock()
        self._dead: Optional[BaseException] = None
        self._result: Optional[Path] = None
        self._finalized = False

    # -- life cycle --------------------------------------------------------------------------------
    def start(self) -> None:
        """Launch the child and the sender/receiver threads (idempotent; :meth:`open` calls it).

        Raises:
            WriterProcessError: the child could not be launched (the OS error, and the param that avoids it).
        """
        if self._proc is not None:
            return
        mine, theirs = socket.socketpair()
        fd = theirs.fileno()
        command = [sys.executable, "-m", self.child_module, str(fd)]
        try:
            self._proc = subprocess.Popen(command, pass_fds=(fd,), stdin=subprocess.DEVNULL)
        except OSError as err:
            mine.close()
            raise WriterProcessError(
                f"cannot start the {self.child_role} ({' '.join(command[:3])}): {err}; {self.avoid_hint}"
            ) from err
        finally:
            theirs.close()
        self._conn = Connection(mine.detach())
        for target, name in ((self._send_loop, "lerobot-writer-send"), (self._receive_loop, "lerobot-writer-receive")):
            threading.Thread(target=target, name=name, daemon=True).start()

    @property
    def pid(self) -> Optional[int]:
        """The child's process id (``None`` before :meth:`start`)."""
        return self._proc.pid if self._proc is not None else None

    def open(
        self, root: Path, *args: Any, streamed: Iterable[str] = (), remote: Optional[dict] = None, **kwargs: Any
    ) -> Future:
        """Create the dataset at ``root`` in the child (``DatasetWriter``'s arguments); the
        features in ``streamed`` come with :meth:`stream_frames` instead of with the episode,
        or, with ``remote`` (:meth:`~embodichain_lerobot.encoder_pool.EncoderPool.remote`), as
        videos finished by the encoder processes."""
        self.start()
        self.root, self.streamed = Path(root), frozenset(streamed)
        return self.submit("open", (str(root), args, kwargs, sorted(self.streamed), remote))

    def finalize(self) -> Optional[Path]:
        """Finalize the dataset in the child (after every message before) and stop it (idempotent)."""
        if self._finalized:
            return self._result
        self._finalized = True
        if self._proc is None:
            return None
        if self.root == Path():  # started, never opened: no dataset, nothing to save or wait for
            self._proc.kill()
            self._stop()
            return None
        if self._dead is not None and self.dead_reported:  # said once already: finish the folder quietly
            self._stop()
            finish_orphaned(self.root)
            self._result = self.root if self.root.is_dir() else None
            return self._result
        try:
            path = self.submit("finalize", None).result(_REPLY_TIMEOUT_S)
            self._result = Path(path) if path else None
        except BaseException:
            if self.root != Path() and self.root.is_dir() and not any(self.root.iterdir()):
                self.root.rmdir()  # reserved, but the child died before it created anything
            elif self.root != Path() and self._dead is not None:
                finish_orphaned(self.root)
            raise
        finally:
            self._stop()
        return self._result

    # -- episodes ----------------------------------------------------------------------------------
    def subtask_index(self, subtask: str) -> int:
        """The stable index of ``subtask`` (the child learns it with the next episode)."""
        return self._subtasks.setdefault(subtask, len(self._subtasks))

    def stream_frames(self, snapshot: dict, env_ids: list[int]) -> None:
        """Send the streamed features of ``snapshot``'s rows ``env_ids``: frame t of those envs' live episodes."""
        keys = sorted(self.streamed)
        self.post("frames", lambda: ({k: _rows(snapshot[k], env_ids) for k in keys}, env_ids))

    def restart(self, env_ids: list[int]) -> None:
        """The live episodes of ``env_ids`` end without a commit: their streamed frames are dropped."""
        if self.streamed and env_ids:
            self.post("restart", list(env_ids))

    def submit_episode(
        self,
        env_id: int,
        frames: Iterable[dict],
        record: dict,
        ticket: Optional[tuple[str, int]] = None,
        after: Optional[threading.Event] = None,
    ) -> Future:
        """Send one committed episode; the future gives its lerobot episode index once published.

        With ``ticket`` (a name and the encoder process's pid, from
        :meth:`~embodichain_lerobot.encoder_pool.EncoderPool.finish`) its videos are the ones that
        encoder process finishes under that name; the
        message then leaves only once ``after`` is set (the encoder process has been sent the
        finish): a dataset writer that holds the episode never waits for a video nobody finishes.
        """
        columns, length = to_columns(frames, self.streamed)
        subtasks = sorted(self._subtasks, key=self._subtasks.__getitem__)
        payload: Any = (env_id, columns, length, record, subtasks, ticket)
        if after is not None:
            ready, message = after, payload
            payload = lambda: ready.wait() and message  # noqa: E731  (on the sender thread)
        future = self.submit("episode", payload, frames=length)
        future.env_id = env_id  # type: ignore[attr-defined]
        return future

    def write_episode(self, frames: Iterable[dict], record: dict, **videos: Any) -> int:
        """Send one episode and wait until the child has published it; its lerobot episode index
        (``videos``: :meth:`submit_episode`'s ``ticket`` and ``after``)."""
        future = self.submit_episode(int(record.get("env_id", 0)), frames, record, **videos)
        return int(future.result(_REPLY_TIMEOUT_S))

    # -- messages ----------------------------------------------------------------------------------
    def post(self, command: str, payload: Any, on_sent: Optional[threading.Event] = None) -> None:
        """Queue a message that gets no reply (``payload`` may be a callable, called on the sender thread);
        ``on_sent`` is set once it has left (or is known never to leave: the child is gone)."""
        self._room.acquire()
        self._outbox.put((command, payload, None, on_sent))

    def submit(self, command: str, payload: Any, frames: int = 0) -> Future:
        """Queue a message; the future completes with the child's reply (or its error).

        The sender thread files the future as waiting just before it sends the message (one
        ``put`` here: a Ctrl-C cannot leave a future without its message), and the receiver
        counts an episode (``frames`` long) before it completes the future.
        """
        future: Future = Future()
        future.frames = frames  # type: ignore[attr-defined]
        with self._lock:
            dead = self._dead
        if dead is not None:
            future.set_exception(dead)
            return future
        self._room.acquire()
        self._outbox.put((command, payload, future, None))
        return future

    def _send_loop(self) -> None:
        while True:
            item = self._outbox.get()
            if item is _STOP or self._conn is None:
                return
            self._room.release()
            command, payload, future, on_sent = item
            try:
                self._send(command, payload, future)
            finally:
                if on_sent is not None:
                    on_sent.set()

    def _send(self, command: str, payload: Any, future: Optional[Future]) -> None:
        """Send one message of the outbox (the sender thread)."""
        with self._lock:
            dead = self._dead
            if future is not None and dead is None:
                self._waiting.append(future)  # filed before the message leaves: replies come in order
        if dead is not None:
            if future is not None:
                if getattr(future, "frames", 0):
                    self.lost_episodes.append(int(getattr(future, "env_id", -1)))
                future.set_exception(dead)
            return
        try:
            message = (command, payload() if callable(payload) else payload)
        except Exception as err:  # a frame that cannot be read: its episode's save reports the gap
            print(f"embodichain writer: cannot send {command!r}: {err!r}", file=sys.stderr)
            if future is not None:
                with self._lock:
                    self._waiting.remove(future)
                future.set_exception(err)
            return
        try:
            self._conn.send(message)  # type: ignore[union-attr]
        except (OSError, ValueError):  # the child is gone: the receiver fails the waiting calls
            return
        if command == "episode":
            self.sent_episodes += 1

    def _receive_loop(self) -> None:
        conn = self._conn
        while conn is not None:
            try:
                status, value = conn.recv()
            except (EOFError, OSError):
                return self._child_died()
            with self._lock:
                future = self._waiting.popleft() if self._waiting else None
                frames = int(getattr(future, "frames", 0))
                if future is not None and status == "ok" and frames and int(value) >= 0:
                    self.num_episodes += 1
                    self.num_frames += frames
            if future is None:
                continue
            if status == "error":
                future.set_exception(value)
            else:
                future.set_result(value)

    def _child_died(self) -> None:
        if self._proc is not None:
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
        code = self._proc.poll() if self._proc is not None else None
        with self._lock:
            waiting, self._waiting = list(self._waiting), collections.deque()
            self.lost_episodes = [int(getattr(f, "env_id", -1)) for f in waiting if getattr(f, "frames", 0)]
            self.exit_code = code
            err = WriterProcessError(self.death_message())
            self._dead = err
        for future in waiting:
            if not future.done():
                future.set_exception(err)

    def death_message(self) -> str:
        """One block: the child died, what is saved (``meta/info.json``), which finished episodes
        were lost (as known now), and what to do."""
        from embodichain_lerobot.folders import folder_status

        text = f"the dataset writer process exited (code {self.exit_code}; its own error, if any, is on stderr above)"
        if self.root == Path():
            return text + "; no dataset yet"
        self.saved_at_death = folder_status(self.root).episodes
        text += f": {self.saved_at_death} episode(s) are saved in {self.root} and load as they are"
        if self.lost_episodes:
            first, count = self.saved_at_death, len(self.lost_episodes)
            numbers = f"episode {first}" if count == 1 else f"episodes {first}-{first + count - 1}"
            text += (
                f"; {count} finished episode(s) (env ids {self.lost_episodes}) were not saved: the writer process "
                f"died before writing them (they would have been {numbers} of the dataset)"
            )
        return text + "; run the command again to record more (into a new folder beside it)"

    def _stop(self) -> None:
        self._outbox.put(_STOP)
        if self._proc is not None:
            try:
                self._proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        if self._conn is not None:
            self._conn.close()
