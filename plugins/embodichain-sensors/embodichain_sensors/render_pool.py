"""Render envs in parallel: ``K`` OpenGL renderers, each used by one worker thread at a time.

MuJoCo releases the GIL inside ``mjr_render`` and ``mjr_readPixels``, and an OpenGL context
can be current in one thread at a time; with one :class:`SensorRenderer` per worker, ``K``
envs rasterize at once. Env ``i`` goes to renderer ``i % K``: the calling thread fills that
renderer's scene (``mjv_updateScene`` needs no GL context and reads the shared per-env
model/data buffers, so it stays on the calling thread), then a worker binds the renderer's
context, renders the env's views and unbinds it. Images are the same as with one renderer:
every renderer is built from the same model with the same settings.

Example:
    >>> pool = RenderPool(lambda: SensorRenderer(model, 320, 180), threads=2)  # doctest: +SKIP
    >>> pool.run(num_envs, prepare=fill_scene, render=render_env)
    >>> pool.close()
"""

from __future__ import annotations

import os
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Callable, Optional

from embodichain_sensors.renderer import SensorRenderer


def render_thread_count(setting: Any, num_envs: int) -> int:
    """The threads a camera's ``render_threads`` asks for, at most ``num_envs``: ``"auto"`` is
    one per core this process may use but one, which is left to the recorder's writer process.

    Example:
        >>> render_thread_count(4, num_envs=2)
        2
    """
    if setting == "auto":
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        setting = cores - 1
    return max(1, min(int(setting or 1), int(num_envs)))


class RenderPool:
    """``threads`` renderers and as many worker threads.

    Args:
        make: builds one renderer (called ``threads`` times on the calling thread).
        threads: renderers and worker threads (>= 1).
    """

    def __init__(self, make: Callable[[], SensorRenderer], threads: int):
        self.renderers: list[SensorRenderer] = []
        try:
            for _ in range(max(1, int(threads))):
                renderer = make()
                renderer.release_current()  # bound by each job on its worker
                self.renderers.append(renderer)
        except BaseException:
            self.close()
            raise
        self._executor: Optional[ThreadPoolExecutor] = ThreadPoolExecutor(
            max_workers=len(self.renderers), thread_name_prefix="embodichain-render"
        )

    @property
    def threads(self) -> int:
        return len(self.renderers)

    def run(
        self,
        num_envs: int,
        prepare: Callable[[SensorRenderer, int], None],
        render: Callable[[SensorRenderer, int], None],
    ) -> None:
        """For every env ``i``: ``prepare(renderer, i)`` on this thread, then
        ``render(renderer, i)`` on a worker with the renderer's context current.

        Returns when every env is rendered; the first error of a job is raised after
        all jobs have stopped (no worker is left writing into the caller's buffers).
        """
        if self._executor is None:
            raise RuntimeError("the render pool is closed")
        pending: list[Optional[Future]] = [None] * self.threads
        error: Optional[BaseException] = None
        try:
            for i in range(num_envs):
                k = i % self.threads
                if pending[k] is not None:
                    pending[k].result()  # type: ignore[union-attr]  # the renderer is free again
                prepare(self.renderers[k], i)
                pending[k] = self._executor.submit(_bound, render, self.renderers[k], i)
        except BaseException as err:
            error = err
        for future in pending:  # wait for every job, also after an error
            try:
                if future is not None:
                    future.result()
            except BaseException as err:
                error = error or err
        if error is not None:
            raise error

    def close(self) -> None:
        """Stop the workers and free every renderer's GL resources; idempotent."""
        executor, self._executor = getattr(self, "_executor", None), None
        if executor is not None:
            executor.shutdown(wait=True)
        for renderer in self.renderers:
            renderer.close()
        self.renderers = []


def _bound(render: Callable[[SensorRenderer, int], None], renderer: SensorRenderer, env_id: int) -> None:
    """``render(renderer, env_id)`` with the renderer's context current on this thread only."""
    with renderer.current():
        render(renderer, env_id)
