"""Recognising dataset folders that hold no saved episode: incomplete recordings.

A folder is a dataset once its ``meta/info.json`` counts at least one episode
(the writer publishes that file last, see :mod:`embodichain_lerobot.writer`).
A folder left by a recording that was killed before its first episode was saved
has no ``meta/info.json``, or one with ``total_episodes`` 0, next to partial
``data/``, ``videos/`` or ``.embodichain_staging/`` files. Such a folder is
*incomplete*: the readers refuse it with :class:`IncompleteDatasetError` (it is
never handed to lerobot), and the recorder removes it when it starts again with the
same ``save_path`` and folder prefix, provided that its recording marker shows the
writing process is gone (:func:`~embodichain_lerobot.storage.marker_owner`).
Nothing recorded is lost: such a folder never held a saved episode.
"""

from __future__ import annotations

import json
import logging
import re
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

from embodichain_lerobot.storage import MARKER, marker_owner

STAGING = ".embodichain_staging"
log = logging.getLogger("embodichain_lerobot")


class IncompleteDatasetError(FileNotFoundError):
    """A folder left by a recording that saved no episode: not a dataset."""


@dataclass(frozen=True)
class FolderStatus:
    """What a dataset folder holds.

    Attributes:
        root: the folder.
        episodes: episodes published in ``meta/info.json`` (0 when it is missing).
        readable: ``meta/info.json`` is missing or parses (``False``: leave the folder alone).
        has_marker: a recording marker is present (the recording never finalized).
        owner: the marker's owner while a live process holds it, else ``None``.
        unfinished: the staging folder or the marker is left (the run stopped early).
    """

    root: Path
    episodes: int
    readable: bool
    has_marker: bool
    owner: Optional[dict]
    unfinished: bool

    @property
    def complete(self) -> bool:
        """At least one episode is saved: the folder loads as a dataset."""
        return self.episodes > 0

    @property
    def removable(self) -> bool:
        """Left by a dead recording of this plugin, with no saved episode."""
        return not self.complete and self.readable and self.has_marker and self.owner is None


def folder_status(root: str | Path) -> FolderStatus:
    """The :class:`FolderStatus` of ``root``."""
    root = Path(root).expanduser()
    info, episodes, readable = root / "meta" / "info.json", 0, True
    if info.is_file():
        try:
            episodes = int(json.loads(info.read_text(encoding="utf-8")).get("total_episodes", 0))
        except (OSError, ValueError, TypeError, AttributeError):
            readable = False
    has_marker = (root / MARKER).is_file()
    owner = marker_owner(root) if has_marker else None
    return FolderStatus(root, episodes, readable, has_marker, owner, unfinished=has_marker or (root / STAGING).exists())


def looks_like_recording(root: Path) -> bool:
    """Whether ``root`` holds anything a recorder writes (``meta/``, staging or marker)."""
    return any((root / name).exists() for name in ("meta", STAGING, MARKER, "data", "videos"))


def incomplete_message(status: FolderStatus) -> str:
    """Why ``status.root`` is not a dataset, and what to do about it."""
    root = status.root
    if status.owner is not None:
        who = f"process {status.owner.get('pid', '?')} on {status.owner.get('host', '?')}"
        return (
            f"{root} is being recorded by {who} (started {status.owner.get('started', '?')}) and holds no "
            "saved episode yet; wait for its first episode"
        )
    if not status.readable:
        return f"{root} is not a readable dataset: its meta/info.json cannot be parsed"
    what = "meta/info.json counts 0 episodes" if (root / "meta" / "info.json").is_file() else "no meta/info.json"
    cleanup = (
        "the recorder also removes such folders when it runs again with the same save_path"
        if status.removable
        else "the recorder leaves it alone: it has no recording marker, so it may not be one of its recordings"
    )
    return (
        f"{root} is an incomplete recording, not a dataset ({what}): the recording stopped before its "
        f"first episode was saved, so it holds no episode. Delete the folder; {cleanup}"
    )


def clean_incomplete(save_path: str | Path, prefix: str) -> list[Path]:
    """Remove the incomplete folders ``<save_path>/<prefix>_NNN`` of dead recordings.

    Only folders with a recording marker nobody holds and no saved episode are
    removed (each with a warning naming it); the rest are left alone.

    Returns:
        The removed folders.
    """
    base = Path(save_path).expanduser()
    if not base.is_dir():
        return []
    pattern = re.compile(re.escape(prefix) + r"_(\d{3,})$")
    removed = []
    for path in sorted(p for p in base.iterdir() if pattern.match(p.name) and p.is_dir()):
        if folder_status(path).removable:
            shutil.rmtree(path, ignore_errors=True)
            log.warning(
                "removed incomplete dataset folder %s: a recording stopped before its first "
                "episode was saved there (it held no episode)",
                path,
            )
            removed.append(path)
    return removed
