"""Where a recording goes: output-folder checks, disk-full errors and the recording marker.

* :func:`check_output_dir` runs before anything is built (``run-env`` calls the
  recorder's ``preflight``): the dataset root must be a writable folder on a
  filesystem with at least ``min_free_mb`` MB free.
* :func:`ensure_space` runs before each episode is saved: it needs
  ``max(min_free_mb, 2 x the episode's raw size)`` free, so a filling disk stops the
  run *between* episodes with a :class:`DiskFullError`; an ``ENOSPC`` inside a save
  becomes the same error (:func:`is_disk_full`).
* :class:`RecordingLock` is the marker ``<dataset>/.embodichain_recording``: created
  (and ``flock``-ed) before lerobot writes anything, held while the writer lives and
  removed by ``finalize()``. A marker nobody holds means the recording process died;
  :mod:`embodichain_lerobot.folders` uses it to recognise incomplete folders.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import shutil
import socket
import tempfile
import time
from pathlib import Path
from typing import Optional

from embodichain_core.config.errors import ConfigError

try:
    import fcntl
except ImportError:  # not POSIX: markers are written but liveness is unknown
    fcntl = None  # type: ignore[assignment]

#: The marker file of a recording in progress (see :class:`RecordingLock`).
MARKER = ".embodichain_recording"
#: Default of the recorder's ``min_free_mb`` param.
DEFAULT_MIN_FREE_MB = 256
_MB = 2**20
_FULL_ERRNOS = {errno.ENOSPC, errno.EDQUOT}
_HOW = (
    "set the recorder's params.save_path (or EMBODICHAIN_DEFAULT_DATASET_ROOT when save_path is not "
    "given) to a writable folder with enough space, or pass --filter_dataset_saving to record nothing"
)


class DiskFullError(OSError):
    """The dataset's filesystem is (nearly) full; the episodes saved before are intact."""


def is_disk_full(err: BaseException) -> bool:
    """Whether ``err`` or an exception it was raised from is a full disk (or quota)."""
    seen: set[int] = set()
    current: BaseException | None = err
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        if isinstance(current, OSError) and (
            current.errno in _FULL_ERRNOS or "No space left on device" in str(current)
        ):
            return True
        current = current.__cause__ or current.__context__
    return False


def existing_ancestor(path: Path) -> Path:
    """``path`` or its nearest existing parent."""
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def free_mb(path: str | os.PathLike) -> float:
    """Free megabytes (for this user) on the filesystem that holds (or will hold) ``path``."""
    return shutil.disk_usage(existing_ancestor(Path(path))).free / _MB


def check_output_dir(save_path: str | os.PathLike, min_free_mb: int, key: str) -> Path:
    """Check that datasets can be written under ``save_path`` (nothing is created).

    Args:
        save_path: the dataset root (it may not exist yet).
        min_free_mb: megabytes that must be free on its filesystem.
        key: the config key that sets ``save_path`` (named in the errors).

    Raises:
        ConfigError: ``save_path`` is a file, not writable, or on a filesystem with too little space.
    """
    path = Path(save_path).expanduser()
    base = existing_ancestor(path)
    if not base.is_dir():
        raise ConfigError(key, f"dataset folder {path} cannot be created: {base} is not a directory; {_HOW}")
    try:
        fd, probe = tempfile.mkstemp(prefix=".embodichain_probe_", dir=base)
        os.close(fd)
        os.unlink(probe)
    except OSError as err:
        where = "" if base == path else f" (it would be created in {base})"
        raise ConfigError(key, f"dataset folder {path} is not writable{where}: {err.strerror or err}; {_HOW}") from err
    free = free_mb(base)
    if free < min_free_mb:
        raise ConfigError(
            key,
            f"only {free:.0f} MB free on the filesystem of the dataset folder {path}; the "
            f"recorder needs at least {min_free_mb} MB (its params.min_free_mb); free space, "
            f"lower min_free_mb, or {_HOW}",
        )
    return path


def ensure_space(path: str | os.PathLike, episode_bytes: int, min_free_mb: int, what: str) -> None:
    """Raise :class:`DiskFullError` unless ``max(min_free_mb, 2 x episode_bytes)`` is free.

    Args:
        path: the dataset folder (or the root it goes into).
        episode_bytes: raw size of the episode about to be saved.
        min_free_mb: the recorder's ``min_free_mb``.
        what: the episode and dataset, for the message.
    """
    need = max(min_free_mb * _MB, 2 * episode_bytes) / _MB
    free = free_mb(path)
    if free < need:
        raise DiskFullError(
            errno.ENOSPC,
            f"not enough disk space to save {what}: {free:.0f} MB free on the "
            f"filesystem of {path}, {need:.0f} MB needed (min_free_mb or twice "
            f"the episode's raw size); free space or {_HOW}",
        )


class RecordingLock:
    """The marker ``<root>/.embodichain_recording`` of a live recording.

    It is written under a temporary name, locked with ``flock`` and renamed into
    place, so a folder's marker is never seen unlocked while its writer lives.
    The lock dies with the process (also on ``SIGKILL``).
    """

    def __init__(self, root: Path):
        self.path = Path(root) / MARKER
        tmp = self.path.with_name(f"{MARKER}.{os.getpid()}.tmp")
        self._fd: Optional[int] = os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        locked = fcntl is not None
        try:
            if locked:
                fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # a filesystem without flock (some network mounts): liveness unknown
            locked = False
        owner = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "locked": locked,
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        os.write(self._fd, json.dumps(owner).encode())
        os.replace(tmp, self.path)

    def release(self) -> None:
        """Remove the marker and drop the lock (idempotent)."""
        if self._fd is None:
            return
        try:
            self.path.unlink(missing_ok=True)
        finally:
            os.close(self._fd)
            self._fd = None


def marker_owner(root: Path) -> Optional[dict]:
    """The owner (pid, host, started) of ``root``'s marker when a live process holds it.

    Returns ``None`` when there is no marker or nobody holds it (the writer died).
    A marker written without a lock (no ``flock`` on that platform or filesystem) is
    taken as held: its writer's liveness cannot be told, so it is never removed.
    """
    path = Path(root) / MARKER
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return None
    try:
        try:
            owner = json.loads(os.read(fd, 4096) or b"{}")
        except ValueError:
            owner = {}
        owner = owner if isinstance(owner, dict) else {}
        if fcntl is None or owner.get("locked") is False:
            return owner
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return owner  # held by a live recording
        return None
    finally:
        os.close(fd)  # also drops the lock we may have taken


def finish_orphaned(root: Path) -> bool:
    """Finish the folder of a writer that died after publishing episodes: remove its staging
    folder and its marker (nobody holds it), as the writer's ``finalize()`` would have.

    Every published episode stays (the staging folder only holds unpublished files). A folder
    with no published episode (the writer died before its first save) is removed: it was
    reserved by this recording and holds nothing saved. A folder whose marker is still held
    (a live writer) is left alone.

    Returns:
        Whether the folder was finished (or removed).
    """
    from embodichain_lerobot.encoder_files import ENCODING
    from embodichain_lerobot.folders import STAGING, folder_status

    status = folder_status(root)
    if status.owner is not None or not status.readable:
        return False
    if not status.complete:
        shutil.rmtree(root, ignore_errors=True)
        return True
    shutil.rmtree(Path(root) / STAGING, ignore_errors=True)
    shutil.rmtree(Path(root) / ENCODING, ignore_errors=True)
    (Path(root) / MARKER).unlink(missing_ok=True)
    return True


class _EncoderDiskFull(logging.Filter):
    """Drops lerobot's ``Encoder thread error: [Errno 28] ...`` log lines: the same error reaches
    the save, which reports it once as a :class:`DiskFullError`."""

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        if not message.startswith("Encoder thread error"):
            return True
        return not any(mark in message for mark in ("Errno 28", "No space left", "Errno 122", "quota"))


_ENCODER_FILTER = _EncoderDiskFull()


def quiet_encoder_disk_full() -> None:
    """Install the filter of lerobot's per-encoder-thread disk-full log lines on the root logger (idempotent)."""
    root = logging.getLogger()
    if _ENCODER_FILTER not in root.filters:
        root.addFilter(_ENCODER_FILTER)
