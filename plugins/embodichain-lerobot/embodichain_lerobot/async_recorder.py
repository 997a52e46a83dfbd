"""``AsyncLeRobotRecorder``: the LeRobot recorder with writing on a worker thread.

A commit hands the episode (already an owned numpy copy, so later buffer changes
cannot touch it) to one daemon worker thread, which does ``add_frame``,
``save_episode`` (PNG/video encoding) and the crash-safe publish in commit
order. Stepping waits only when ``max_pending_episodes`` episodes are queued
(0: never). A worker error is raised at the next commit, step or ``finalize()`` (a
:class:`~embodichain_lerobot.storage.DiskFullError` as itself, others wrapped);
``finalize()`` drains the queue first, so every committed episode is written
(a ``SIGKILL`` loses the queued ones), and rejects later commits.
"""

from __future__ import annotations

import queue
import threading
from typing import Any, Optional

from embodichain_lerobot.episodes import Episode
from embodichain_lerobot.recorder import LeRobotRecorder, log
from embodichain_lerobot.storage import DiskFullError

_STOP = object()


class AsyncLeRobotRecorder(LeRobotRecorder):
    """Same dataset as :class:`LeRobotRecorder`; writes on a worker thread."""

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._queue: queue.Queue = queue.Queue(maxsize=self.params.max_pending_episodes)
        self._errors: list[BaseException] = []
        self._reported = 0
        self._lock = threading.Lock()
        self._thread: Optional[threading.Thread] = None

    @property
    def pending_episodes(self) -> int:
        """Committed episodes not written yet."""
        return self._queue.qsize()

    def _write(self, episode: Episode) -> None:
        self._raise_worker_errors()
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="lerobot-recorder", daemon=True)
            self._thread.start()
        self._queue.put(episode)

    def record_step(self, *args: Any, **kwargs: Any) -> None:
        self._raise_worker_errors()
        super().record_step(*args, **kwargs)

    def _work(self) -> None:
        while True:
            item = self._queue.get()
            try:
                if item is _STOP:
                    return
                self._write_now(item)
            except BaseException as err:  # reported on the recording thread
                log.error("writing an episode of env %s failed: %r", getattr(item, "env_id", "?"), err)
                with self._lock:
                    self._errors.append(err)
            finally:
                self._queue.task_done()

    def _raise_worker_errors(self, final: bool = False) -> None:
        with self._lock:
            new = self._errors[self._reported :] if not final else self._errors
            self._reported = len(self._errors)
        if not new:
            return
        if isinstance(new[0], DiskFullError):  # its message says what happened and what to do
            raise new[0]
        detail = "; ".join(repr(e) for e in new[:5]) + (f"; ... ({len(new)} errors)" if len(new) > 5 else "")
        raise RuntimeError(f"{type(self).__name__}: writing {len(new)} episode(s) failed: {detail}") from new[0]

    def wait(self) -> None:
        """Block until every queued episode is written (errors are raised)."""
        if self._thread is not None:
            self._queue.join()
        self._raise_worker_errors()

    def finalize(self) -> Optional[str]:
        """Drain the queue, finalize the dataset, then raise the worker errors (if any)."""
        if self._finalized:
            return self._path
        if self._thread is not None:
            self._queue.put(_STOP)
            self._thread.join()
        path = super().finalize()
        self._raise_worker_errors(final=True)
        return path
