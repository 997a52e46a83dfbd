"""``AsyncLeRobotRecorder``: the LeRobot recorder with writing on a worker thread.

A commit hands the episode (already an owned numpy copy, so later buffer changes
cannot touch it) to one daemon worker thread, which does ``add_frame``,
``save_episode`` (PNG/video encoding) and the crash-safe publish in commit
order. By default (``params.writer_process``) the worker thread only sends the
episode to a child process that does that work
(:mod:`embodichain_lerobot.writer_process`): lerobot's Python then never competes
with stepping and rendering for this process's GIL, and lerobot is imported there
while the first episodes run (the child starts with the first recorded observation). Stepping waits only when ``max_pending_episodes`` episodes are
queued (0: never). A worker error is raised at the next commit, step or ``finalize()`` (a
:class:`~embodichain_lerobot.storage.DiskFullError` as itself, others wrapped);
``finalize()`` drains the queue first, so every committed episode is written, and
rejects later commits. ``saved_episodes`` counts an episode only once it is published
(loadable after any kill). After a ``SIGKILL`` of the recording process the writer
process still writes every episode it had received (they are sent as they are
committed), then finalizes; :meth:`AsyncLeRobotRecorder.wait` blocks until everything
committed is published (``embodichain generate``'s workers call it before they report).
"""

from __future__ import annotations

import queue
import threading
from concurrent.futures import Future
from concurrent.futures import wait as futures_wait
from typing import Any, Optional

from embodichain_lerobot.episodes import Episode
from embodichain_lerobot.recorder import LeRobotRecorder, log
from embodichain_lerobot.storage import DiskFullError
from embodichain_lerobot.writer_process import WriterProcessError

_STOP = object()


class AsyncLeRobotRecorder(LeRobotRecorder):
    """Same dataset as :class:`LeRobotRecorder`; writes on a worker thread (by default
    through a writer process, ``params.writer_process``)."""

    default_writer_process = True

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self._queue: queue.Queue = queue.Queue(maxsize=self.params.max_pending_episodes)
        self._errors: list[BaseException] = []
        self._reported = 0
        self._lock = threading.Lock()
        self._thread: Optional[threading.Thread] = None
        self._futures: list[Future] = []  # episodes sent to the writer process, not written yet

    @property
    def pending_episodes(self) -> int:
        """Committed episodes not written yet."""
        return self._queue.qsize() + sum(not f.done() for f in self._futures)

    def _write(self, episode: Episode) -> None:
        self._raise_worker_errors()
        if self._writer_process is not None:
            return self._submit(episode)
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="lerobot-recorder", daemon=True)
            self._thread.start()
        self._queue.put(episode)

    def _submit(self, episode: Episode) -> None:
        """Send the episode to the writer process now (in order with the streamed frames);
        its reply completes a future (errors are reported like the worker thread's)."""
        _, frames, record = self._prepare(episode)
        videos = self._episode_videos(episode.env_id)  # with encoder processes: the one finishing its videos
        future = self._writer_process.submit_episode(episode.env_id, frames, record, **videos)  # type: ignore[union-attr]
        future.add_done_callback(lambda f: self._written(f, episode.env_id, len(episode)))
        self._futures = [f for f in self._futures if not f.done()] + [future]
        bound = self.params.max_pending_episodes
        while bound and len(self._futures) > bound:  # stepping waits for the oldest
            futures_wait(self._futures[:1])
            self._futures = [f for f in self._futures if not f.done()]

    def _written(self, future: Future, env_id: int, length: int) -> None:
        err = future.exception()
        if err is None:
            log.info("saved episode %s of env %d (%d frames) to %s", future.result(), env_id, length, self.dataset_path)
            return
        if not isinstance(err, WriterProcessError):  # a dead writer is told once, when it is raised
            log.error("writing an episode of env %s failed: %r", env_id, err)
        with self._lock:
            self._errors.append(err)

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

    def _raise_worker_errors(self) -> None:
        """Raise the write errors not raised before (each is raised once)."""
        with self._lock:
            new = self._errors[self._reported :]
            self._reported = len(self._errors)
        if not new:
            return
        proc = self._writer_process
        if isinstance(new[0], WriterProcessError) and proc is not None and proc.exit_code is not None:
            futures_wait(self._futures, timeout=10)  # every episode sent is now written or known lost
            proc.dead_reported = True  # its finalize() then finishes the folder quietly
            raise WriterProcessError(proc.death_message()) from None
        if isinstance(new[0], (DiskFullError, WriterProcessError)):  # its message says what happened and what to do
            raise new[0]
        detail = "; ".join(repr(e) for e in new[:5]) + (f"; ... ({len(new)} errors)" if len(new) > 5 else "")
        raise RuntimeError(f"{type(self).__name__}: writing {len(new)} episode(s) failed: {detail}") from new[0]

    def wait(self) -> None:
        """Block until every queued episode is written (errors are raised)."""
        if self._thread is not None:
            self._queue.join()
        futures_wait(self._futures)
        self._raise_worker_errors()

    def finalize(self) -> Optional[str]:
        """Drain the queue, finalize the dataset, then raise the worker errors not raised before (if any)."""
        if self._finalized:
            return self._path
        if self._thread is not None:
            self._queue.put(_STOP)
            self._thread.join()
        futures_wait(self._futures)  # the writer process also finishes them before it finalizes
        path = super().finalize()
        self._raise_worker_errors()
        return path
