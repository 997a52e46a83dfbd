"""The driver's Ray: joining a cluster or starting a local instance that ends with the driver.

``ray.init`` replaces the driver's ``SIGTERM`` handler (with Python's ``sys.exit`` and its core
worker's crash dump, which aborts the process): :func:`init_ray` puts the handler back, so a
``SIGTERM`` of ``generate`` stops it the way a Ctrl-C does. A local instance is watched by a
:class:`~embodichain_ray.reaper.Reaper`, so none of its processes outlives the driver. Ray's
own ``A worker died or was killed ...`` notes are left out: the driver says which worker died,
with which episodes, and what happens now (:mod:`embodichain_ray.faults`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
from collections.abc import Iterator
from typing import Any

from embodichain_ray.reaper import Reaper, start_reaper
from embodichain_ray.spec import GenerateSpec


def init_ray(spec: GenerateSpec) -> Reaper | None:
    """Join ``spec.ray_address``, or start a small local Ray sized to the workers.

    ``ray.init`` installs its own ``SIGTERM`` handlers (Python's ``sys.exit`` and its core
    worker's crash dump, which aborts the process); the handler this process had before is
    put back, so a ``SIGTERM`` stops ``generate`` the way a Ctrl-C does. A local instance
    comes with its :class:`~embodichain_ray.reaper.Reaper` (stop it after ``ray.shutdown()``):
    none of its processes outlives the driver by more than a few seconds, whatever ends it;
    its workers do not take their dataset writers with them (Ray's
    ``kill_child_processes_on_worker_exit`` is off), so a writer orphaned by a kill still
    writes the episodes it had received.
    """
    import ray

    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    quiet_worker_death_notes()
    with _keep_sigterm_handler():
        if spec.ray_address:  # the cluster's own settings (token authentication included) apply
            ray.init(address=spec.ray_address, log_to_driver=False, logging_level=logging.ERROR)
            return None
        os.environ.setdefault("RAY_AUTH_MODE", "disabled")  # a private instance: no token file in ~/.ray
        # a worker that exits because its raylet is gone (the driver was killed) leaves its dataset
        # writer alone: the writer writes the episodes it had received, finalizes and exits
        os.environ.setdefault("RAY_kill_child_processes_on_worker_exit", "false")
        reaper = start_reaper()
        try:
            ray.init(
                address="local",  # a new instance, whatever `ray start` or a test cluster left behind
                num_cpus=spec.workers,
                include_dashboard=spec.dashboard,
                object_store_memory=80 * 2**20,
                log_to_driver=False,
                logging_level=logging.ERROR,
                configure_logging=True,
            )
        except BaseException:
            if reaper is not None:
                reaper.stop()
            raise
    return reaper


@contextlib.contextmanager
def _keep_sigterm_handler() -> Iterator[None]:
    """Restore this process's ``SIGTERM`` handler after the block (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handler = signal.getsignal(signal.SIGTERM)
    try:
        yield
    finally:
        if handler is not None:  # None: installed outside Python, nothing to restore
            signal.signal(signal.SIGTERM, handler)


def quiet_worker_death_notes() -> None:
    """Drop the raylet's ``A worker died or was killed ...`` notes that Ray prints on the driver:
    :meth:`Scheduler._collect` says in words which worker died, with which episodes, and what
    happens now. Other messages of Ray are printed as before (a no-op if Ray has no such hook)."""
    try:
        import ray._private.worker as ray_worker
    except ImportError:
        return
    printer = getattr(ray_worker, "print_to_stdstream", None)
    if printer is None or getattr(printer, "embodichain_quiet", False):
        return

    def filtered(data: dict, *args: Any, **kwargs: Any) -> None:
        lines = [
            line
            for line in data.get("lines", [])
            if not (data.get("pid") == "raylet" and str(line).startswith("A worker died or was killed"))
        ]
        if lines:
            printer({**data, "lines": lines}, *args, **kwargs)

    filtered.embodichain_quiet = True  # type: ignore[attr-defined]
    ray_worker.print_to_stdstream = filtered
