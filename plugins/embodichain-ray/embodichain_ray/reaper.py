"""The embedded Ray instance ends with the driver, whatever ends the driver.

Ray ties the processes that ``ray.init`` starts itself (GCS, raylet, log monitor) to the
driver with the kernel's parent-death signal, but not the ones the raylet starts: after a
``SIGKILL`` of the driver its dashboard agent and runtime-env agent try to report to a
GCS that is gone and stay alive for a minute or more. :func:`start_reaper` starts a
small watchdog (``python -m embodichain_ray.reaper DRIVER_PID``) in its own session, so a
Ctrl-C or a ``SIGTERM`` of the driver's process group does not reach it. It holds the
read end of a pipe whose write end only the driver has, and notes the driver's new
descendant processes every :data:`WATCH_INTERVAL_S` seconds. When the pipe closes (the
driver called :meth:`Reaper.stop` after ``ray.shutdown()``, or it died, even by
``SIGKILL``) it gives them :data:`GRACE_S` seconds to exit, then kills the ones left.

Processes that existed before the watchdog started are never touched, and neither are the
dataset writer processes of the workers (``embodichain_lerobot.writer_child``): a writer
orphaned by a killed worker writes the episodes it had received, finalizes its shard
and exits by itself. Linux only (``/proc``); elsewhere :func:`start_reaper` returns ``None``.
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Optional

#: Seconds between two looks at the driver's descendants.
WATCH_INTERVAL_S = 0.5
#: Seconds the driver's descendants get to exit by themselves once the driver is gone.
GRACE_S = 2.0
#: Command-line fragments of descendants that are left alone (they end by themselves).
SPARED = ("embodichain_lerobot.writer_child",)


class Reaper:
    """The driver's handle on the watchdog process: :meth:`stop` once Ray is shut down."""

    def __init__(self, proc: subprocess.Popen, write_fd: int):
        self.proc, self._fd = proc, write_fd

    def stop(self) -> None:
        """Close the pipe: the watchdog kills what is left of Ray after :data:`GRACE_S` s (idempotent)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def start_reaper() -> Optional[Reaper]:
    """Start the watchdog of this process's Ray descendants (``None`` where ``/proc`` is missing)."""
    if not Path("/proc/self/stat").is_file():
        return None
    read_fd, write_fd = os.pipe()  # not inheritable: Ray's processes never hold the write end
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "embodichain_ray.reaper", str(os.getpid())],
            stdin=read_fd,
            stdout=subprocess.DEVNULL,
            start_new_session=True,
        )
    except OSError:
        os.close(write_fd)
        return None
    finally:
        os.close(read_fd)
    return Reaper(proc, write_fd)


def _stat(pid: int) -> Optional[tuple[int, int]]:
    """``(parent pid, start time in clock ticks)`` of ``pid``, or ``None`` once it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return int(fields[1]), int(fields[19])
    except (OSError, IndexError, ValueError):
        return None


def descendants(root: int) -> dict[int, int]:
    """Every live descendant of ``root``: pid -> start time."""
    children: dict[int, list[int]] = {}
    starts: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (stat := _stat(int(entry))) is not None:
            children.setdefault(stat[0], []).append(int(entry))
            starts[int(entry)] = stat[1]
    found, todo = {}, list(children.get(root, []))
    while todo:
        pid = todo.pop()
        if pid in starts and pid not in found:
            found[pid] = starts[pid]
            todo.extend(children.get(pid, []))
    return found


def _spared(pid: int) -> bool:
    try:
        command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return True  # gone already
    return any(fragment in command for fragment in SPARED)


def _alive(pids: dict[int, int]) -> dict[int, int]:
    """The entries of ``pids`` still running (same pid and start time: never a reused pid)."""
    return {pid: start for pid, start in pids.items() if (stat := _stat(pid)) is not None and stat[1] == start}


def watch(driver: int, pipe_fd: int = 0) -> dict[int, int]:
    """Note the driver's new descendants until ``pipe_fd`` reaches end of file; what was noted."""
    before, me = set(descendants(driver)), os.getpid()
    noted: dict[int, int] = {}
    while True:
        ready, _, _ = select.select([pipe_fd], [], [], WATCH_INTERVAL_S)
        if ready and not os.read(pipe_fd, 4096):
            return noted
        for pid, start in descendants(driver).items():
            if pid != me and pid not in before and pid not in noted and not _spared(pid):
                noted[pid] = start


def reap(noted: dict[int, int], grace: float = GRACE_S) -> list[int]:
    """Give ``noted`` ``grace`` seconds to exit, then ``SIGKILL`` the ones left; the pids killed."""
    deadline = time.monotonic() + grace
    while _alive(noted) and time.monotonic() < deadline:
        time.sleep(0.1)
    killed = []
    for pid in _alive(noted):
        try:
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
        except OSError:
            pass
    return killed


def main(argv: Optional[list[str]] = None) -> None:
    """Entry point of the watchdog: ``python -m embodichain_ray.reaper DRIVER_PID`` (the pipe on stdin)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    driver = int((argv if argv is not None else sys.argv[1:])[0])
    reap(watch(driver))


if __name__ == "__main__":
    main()
