"""Storage URIs for shard files: ``s3://``, ``gs://``, ``file://``, a local folder, or any
scheme fsspec knows (``memory://`` in tests).

A URI is opened with ``pyarrow.fs.FileSystem.from_uri`` (local, S3, GCS, HDFS, with their
usual credentials from the environment); a scheme pyarrow does not know goes through
fsspec (``pyarrow.fs.PyFileSystem(FSSpecHandler(...))``). :func:`probe_storage` writes,
reads back and deletes a small object, so an unreachable or read-only location stops a run
before any episode runs.
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Any

#: The ``--transport`` values that are not a URI.
SHARED, RAY = "shared", "ray"
TRANSPORTS = (SHARED, RAY)


class StorageError(RuntimeError):
    """A storage URI that cannot be opened, written or read."""


def storage_target(value: str) -> str:
    """A ``--transport`` value as the run keeps it: ``shared``, ``ray``, a URI, or a local
    folder made absolute (workers may start in another folder)."""
    if value in TRANSPORTS or "://" in value:
        return value
    return str(Path(value).expanduser().absolute())


def open_storage(uri: str) -> tuple[Any, str]:
    """``(pyarrow filesystem, base path)`` of ``uri``.

    Raises:
        StorageError: neither pyarrow nor fsspec can open it (the reason of each).
    """
    import pyarrow.fs as pafs

    if "://" not in uri:
        uri = Path(uri).absolute().as_uri()
    try:
        fs, path = pafs.FileSystem.from_uri(uri)
        return fs, path.rstrip("/")
    except Exception as arrow_err:  # noqa: BLE001  (an unknown scheme: try fsspec)
        try:
            import fsspec

            ffs, path = fsspec.core.url_to_fs(uri)
        except Exception as err:  # noqa: BLE001
            raise StorageError(f"cannot open {uri}: pyarrow: {arrow_err}; fsspec: {err}") from None
        return pafs.PyFileSystem(pafs.FSSpecHandler(ffs)), str(path).rstrip("/")


def probe_storage(uri: str) -> None:
    """Write, read back and delete a small object under ``uri``.

    Raises:
        StorageError: the location cannot be opened, written, read or cleaned (the reason).
    """
    fs, base = open_storage(uri)
    path = f"{base}/.embodichain-probe-{uuid.uuid4().hex[:12]}"
    try:
        fs.create_dir(base, recursive=True)
        with fs.open_output_stream(path) as out:
            out.write(b"embodichain")
        with fs.open_input_stream(path) as src:
            if src.read() != b"embodichain":
                raise StorageError(f"{uri}: an object written there reads back differently")
        fs.delete_file(path)
    except StorageError:
        raise
    except Exception as err:  # noqa: BLE001  (pyarrow's and fsspec's errors, in one message)
        raise StorageError(f"cannot write to {uri}: {type(err).__name__}: {err}") from None


def upload(fs: Any, source: Path, dest: str, chunk: int) -> None:
    """Copy the local file ``source`` to ``dest`` on ``fs`` in ``chunk``-byte pieces."""
    parent = dest.rsplit("/", 1)[0]
    fs.create_dir(parent, recursive=True)
    with open(source, "rb") as src, fs.open_output_stream(dest) as out:
        while piece := src.read(chunk):
            out.write(piece)


def download(fs: Any, source: str, dest: Path, chunk: int) -> None:
    """Copy ``source`` on ``fs`` to the local file ``dest`` in ``chunk``-byte pieces, then delete it there."""
    with fs.open_input_stream(source) as src, open(dest, "wb") as out:
        while piece := src.read(chunk):
            out.write(piece)
    fs.delete_file(source)


def remove_prefix(fs: Any, path: str) -> None:
    """Delete ``path`` and everything under it on ``fs`` (nothing when it is gone already)."""
    import pyarrow.fs as pafs

    if fs.get_file_info(path).type != pafs.FileType.NotFound:
        fs.delete_dir(path)
