"""How a worker's shard reaches the driver: a shared folder, Ray's object store, or storage.

``--transport shared`` (the default): every worker records straight into ``--shards``, a
folder the driver reads too (one machine, or NFS on a cluster). With ``--transport ray``
or a storage URI, a worker records into a *scratch* folder on its own node (``--scratch``,
else the node's ``EMBODICHAIN_GENERATE_SCRATCH``, else its temp folder) that the driver
never reads; after every batch, once its episodes are durable, :class:`ShardSender` ships
what changed in the shard (the new episodes' data, video and metadata files, the updated
small metadata files, the new lines of the episode log, ``meta/info.json`` last) and
:func:`receive` writes them into the driver's copy of the shard under ``--shards``, in
that order, so the copy is a valid shard at every moment (``meta/info.json`` is its commit
point, as in the recorder). Large files travel in pieces of at most :data:`CHUNK_BYTES`:
through the object store (``ray.put`` by the worker, one piece at a time fetched and freed
by the driver) or through the storage URI (uploaded by the worker, downloaded and deleted
by the driver). A worker that dies before the driver has its files takes its pieces with
it; the driver then runs its batch again (:class:`TransferLost`).
"""

from __future__ import annotations

import functools
import json
import os
import tempfile
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from embodichain_lerobot.folders import STAGING
from embodichain_lerobot.storage import MARKER
from embodichain_lerobot.writer import SIDECAR
from embodichain_ray.spec import WORKER_DIR, GenerateSpec
from embodichain_ray.storage import RAY, SHARED, download, open_storage, remove_prefix, upload

#: The largest piece of a file in the object store or in one read/write of storage.
CHUNK_BYTES = 8 * 2**20
#: A worker's scratch folder on its node when ``--scratch`` is not given.
SCRATCH_ENV = "EMBODICHAIN_GENERATE_SCRATCH"
#: Shard files written once and never changed (sent once); the other files are sent when they change.
_WRITE_ONCE = ("data/", "videos/", "meta/episodes/")
_INFO = "meta/info.json"


class TransferLost(RuntimeError):
    """A batch's files could not be fetched (their worker died first): the batch runs again."""


@dataclass
class FileItem:
    """One file of a delivery: its bytes inline, as object-store pieces or as a storage object.

    ``append_at`` (the episode log): the bytes continue the driver's copy at that offset.
    """

    path: str
    data: bytes | None = None
    pieces: list = field(default_factory=list)
    stored: str | None = None
    append_at: int | None = None


@dataclass
class Delivery:
    """What a batch adds to its worker's shard.

    Attributes:
        shard: the shard's folder under the driver's ``--shards`` (``worker-WWW/<name>``).
        records: the episode-log lines of the episodes published since the last batch.
        files: the files to write into the driver's copy, in order (empty: a shared folder).
    """

    shard: str
    records: list = field(default_factory=list)
    files: list = field(default_factory=list)


def scratch_root(spec: GenerateSpec) -> Path:
    """This node's scratch folder for the run's shards (``--scratch``, the node's
    ``EMBODICHAIN_GENERATE_SCRATCH``, or its temp folder)."""
    base = spec.scratch or os.environ.get(SCRATCH_ENV) or os.path.join(tempfile.gettempdir(), "embodichain-generate")
    return Path(base).expanduser()


class ShardSender:
    """A worker's side of the transport: where it records and what each batch ships.

    Args:
        spec: the run.
        worker: the worker's index.
    """

    def __init__(self, spec: GenerateSpec, worker: int):
        self.mode, self.worker = spec.transport, worker
        self.token = uuid.uuid4().hex[:8]  # one per incarnation: a restart anywhere never reuses a name
        if self.mode == SHARED:
            self.save_path = spec.worker_dir(worker)
        else:
            self.save_path = scratch_root(spec) / f"{spec.output.name}-{self.token}" / WORKER_DIR.format(worker)
        self.fs: Any = None
        self.base = ""
        if self.mode not in (SHARED, RAY):
            self.fs, self.base = open_storage(self.mode)
        self._sent: dict[str, tuple[int, int]] = {}
        self._log_at = 0
        self._shard: str | None = None

    def shard_name(self, root: Path) -> str:
        """The shard's folder under the driver's ``--shards``."""
        name = root.name if self.mode == SHARED else f"{root.name}-{self.token}"
        return f"{WORKER_DIR.format(self.worker)}/{name}"

    def collect(self, root: Path | None) -> Delivery | None:
        """What changed in the shard at ``root`` since the last batch (``None``: no episode yet)."""
        if root is None or not (root / _INFO).is_file():
            return None
        delivery = Delivery(self.shard_name(root))
        self._shard = delivery.shard
        text = b""
        if (root / SIDECAR).is_file():
            with open(root / SIDECAR, "rb") as log:  # only what was appended since the last batch
                log.seek(self._log_at)
                text = log.read()
        text = text[: text.rfind(b"\n") + 1]  # whole lines only
        total = int(json.loads((root / _INFO).read_text(encoding="utf-8"))["total_episodes"])
        for line in text.decode("utf-8").splitlines():
            rec = json.loads(line)
            if isinstance(rec.get("lerobot_episode_index"), int) and rec["lerobot_episode_index"] < total:
                delivery.records.append(rec)
        if self.mode != SHARED:
            delivery.files = self._files(root, delivery.shard)
            if text:
                delivery.files.insert(-1, FileItem(SIDECAR, data=text, append_at=self._log_at))
        self._log_at += len(text)
        return delivery

    def _files(self, root: Path, shard: str) -> list[FileItem]:
        items, info = [], None
        for path in sorted(p for p in root.rglob("*") if p.is_file()):
            rel = path.relative_to(root).as_posix()
            if rel.startswith(STAGING) or rel in (MARKER, SIDECAR) or "/." in f"/{rel}":
                continue
            stat = path.stat()
            key = (stat.st_size, stat.st_mtime_ns)
            if self._sent.get(rel) == key or (rel.startswith(_WRITE_ONCE) and rel in self._sent):
                continue
            self._sent[rel] = key
            item = self._large(path, rel, shard) if rel.startswith(_WRITE_ONCE) else FileItem(rel, path.read_bytes())
            if rel == _INFO:
                info = item
            else:
                items.append(item)
        return items + ([info] if info is not None else [])

    def _large(self, path: Path, rel: str, shard: str) -> FileItem:
        if self.fs is not None:
            dest = f"{self.base}/{shard}/{rel}"
            upload(self.fs, path, dest, CHUNK_BYTES)
            return FileItem(rel, stored=dest)
        import ray

        pieces = []
        with open(path, "rb") as src:
            while piece := src.read(CHUNK_BYTES):
                pieces.append(ray.put(piece))
        return FileItem(rel, pieces=pieces)

    def discard(self) -> None:
        """Remove this incarnation's scratch folder (its episodes were delivered)."""
        from embodichain_ray.shards import remove_tree

        if self.mode != SHARED:
            remove_tree(self.save_path.parent)
        if self.fs is not None and self._shard is not None:  # what the driver has not fetched
            remove_prefix(self.fs, f"{self.base}/{self._shard}")


def receive(delivery: Delivery, shards: Path, transport: str) -> Path:
    """Write ``delivery``'s files into the driver's copy of its shard; the shard folder.

    Raises:
        TransferLost: a piece is gone (its worker died before the driver fetched it).
    """
    from ray.exceptions import ObjectLostError

    root = shards / delivery.shard
    fs = _driver_storage(transport) if delivery.files and transport not in (SHARED, RAY) else None
    for item in delivery.files:
        dest = root / item.path
        dest.parent.mkdir(parents=True, exist_ok=True)
        if item.append_at is not None:
            with open(dest, "ab") as out:
                out.truncate(item.append_at)
                out.write(item.data or b"")
            continue
        tmp = dest.with_name(f".{dest.name}.part")
        try:
            _write(item, tmp, fs)
        except (ObjectLostError, FileNotFoundError) as err:
            tmp.unlink(missing_ok=True)
            raise TransferLost(f"{delivery.shard}/{item.path}: {type(err).__name__}") from None
        os.replace(tmp, dest)
    return root


@functools.lru_cache(maxsize=4)
def _driver_storage(uri: str) -> Any:
    """The driver's filesystem of ``uri``, opened once per run."""
    return open_storage(uri)[0]


def _write(item: FileItem, tmp: Path, fs: Any) -> None:
    if item.stored is not None:
        download(fs, item.stored, tmp, CHUNK_BYTES)
        return
    import ray

    with open(tmp, "wb") as out:
        if item.data is not None:
            out.write(item.data)
        for ref in item.pieces:  # one piece in the driver at a time
            out.write(ray.get(ref))
