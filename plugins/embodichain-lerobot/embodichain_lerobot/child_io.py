"""The plumbing shared by the writer and encoder child processes: the socket read on a thread
from the first moment (:class:`Inbox`), the start (signals, priority) and the exit, messages
on stderr, and exceptions made fit to send back."""

from __future__ import annotations

import collections
import os
import pickle
import signal
import sys
import threading
from multiprocessing.connection import Connection
from typing import Any, Optional

from embodichain_lerobot.storage import DiskFullError
from embodichain_lerobot.writer_process import WriterProcessError

#: Bytes of received, unhandled messages above which the child stops reading (:class:`Inbox`).
INBOX_BYTES = 512 * 2**20
#: The child's scheduling priority, relative to the recording process: on a busy machine
#: stepping and rendering go first, and the child (whose inbox holds the frames meanwhile)
#: catches up in their idle time (end to end, the main job ran about 10 % faster than at +0).
NICENESS = 5


def _picklable(err: BaseException) -> BaseException:
    """``err`` if it survives pickling, else a :class:`WriterProcessError` with its text."""
    try:
        pickle.loads(pickle.dumps(err))
        return err
    except Exception:
        kind = DiskFullError if isinstance(err, DiskFullError) else WriterProcessError
        return kind(f"{type(err).__name__}: {err}")


def _say(line: str) -> None:
    """Print ``line`` on stderr, unless stderr is a terminal that the shell has taken back
    (the recording process is gone and the prompt is back: the dataset on disk says the rest)."""
    try:
        if os.isatty(2) and os.tcgetpgrp(2) != os.getpgrp():
            return
    except OSError:
        pass
    print(line, file=sys.stderr, flush=True)


class Inbox:
    """Reads the socket on its own thread from the child's first moment (lerobot's import takes
    seconds, and the recording process must not wait for it), keeping up to ``limit`` bytes of
    messages; above that it stops reading, and the recording process's sender waits."""

    def __init__(self, conn: Connection, limit: int = INBOX_BYTES):
        self._conn, self._limit = conn, limit
        self._messages: collections.deque[bytes] = collections.deque()
        self._bytes, self._closed = 0, False
        self._cv = threading.Condition()
        threading.Thread(target=self._read, name="writer-inbox", daemon=True).start()

    def _read(self) -> None:
        while True:
            try:
                data = self._conn.recv_bytes()
            except (EOFError, OSError):
                break
            with self._cv:
                while self._bytes > self._limit:
                    self._cv.wait()
                self._messages.append(data)
                self._bytes += len(data)
                self._cv.notify_all()
        with self._cv:
            self._closed = True
            self._cv.notify_all()

    def get(self) -> Any:
        """The next message; ``EOFError`` once the recording process is gone and all are read."""
        with self._cv:
            while not self._messages and not self._closed:
                self._cv.wait()
            if not self._messages:
                raise EOFError
            data = self._messages.popleft()
            self._bytes -= len(data)
            self._cv.notify_all()
        return pickle.loads(data)


def start_child(argv: Optional[list[str]]) -> tuple[Connection, "Inbox"]:
    """The first moments of a writer or encoder process: the socket of ``argv[0]`` (a file
    descriptor) read from now on (while lerobot is imported), signals left to the recording
    process (a Ctrl-C or a ``kill`` of the process group reaches the child too), a lower
    priority than the recording (:data:`NICENESS`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    fd = int((argv if argv is not None else sys.argv[1:])[0])
    os.environ.setdefault("SVT_LOG", "1")
    conn = Connection(fd)
    inbox = Inbox(conn)
    try:
        os.nice(NICENESS)
    except OSError:
        pass
    return conn, inbox


def run_child(serve_fn: Any, conn: Connection, inbox: "Inbox") -> None:
    """Serve the recording process's messages until it is done, then exit at once."""
    import av
    import torch

    from embodichain_lerobot.encoding import sampled_video_stats

    torch.set_num_threads(1)  # its few ops here are small: a thread pool would only spin
    av.logging.set_libav_level(av.logging.ERROR)  # FFmpeg's per-video encoder summaries (x264 prints ~12 lines)
    with sampled_video_stats():  # lerobot's sampled statistics, also for encoders started outside a save
        serve_fn(conn, inbox)
    # every file is closed: skip the interpreter's teardown
    # (a second of unloading torch and lerobot that the recording process would wait for)
    sys.stderr.flush()
    os._exit(0)
