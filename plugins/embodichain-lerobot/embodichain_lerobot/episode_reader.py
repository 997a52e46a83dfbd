"""Fast reading of one recorded episode's frames, without ``LeRobotDataset``.

``embodichain dataset preview`` needs a few frames of one episode: importing
lerobot and building a ``LeRobotDataset`` (which memory-maps every column and
decodes each video frame with a seek) takes seconds, so this module reads the
LeRobot v3 files directly: the episode's row of ``meta/episodes``, only the
needed columns of its data parquet file (pyarrow), PNG image cells (Pillow) and
its span of each mp4 (PyAV, decoded in one sequential pass).

Example:
    >>> ep = EpisodeFiles("outputs/datasets/arm7_table_push_000", 0)  # doctest: +SKIP
    >>> frames = ep.camera_frames("observation.images.head", [0, 50, 99])  # doctest: +SKIP
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from embodichain_lerobot.reading import check_dataset_dir


class EpisodeFiles:
    """The files and frame range of episode ``episode`` of the dataset at ``root``.

    Raises:
        IndexError: no such episode.
    """

    def __init__(self, root: str | Path, episode: int):
        self.root = check_dataset_dir(root)
        self.info = json.loads((self.root / "meta" / "info.json").read_text(encoding="utf-8"))
        self.features: dict[str, dict] = self.info["features"]
        self.fps = int(self.info["fps"])
        total = int(self.info.get("total_episodes", 0))
        if not 0 <= episode < total:
            raise IndexError(f"episode {episode} is out of range: the dataset has {total} episode(s)")
        self.episode = episode
        self.meta = self._episode_row()
        self.length = int(self.meta["length"])
        self._table: dict[str, list] = {}

    def _episode_row(self) -> dict[str, Any]:
        import pyarrow.compute as pc
        import pyarrow.parquet as pq

        for path in sorted((self.root / "meta" / "episodes").glob("*/*.parquet")):
            table = pq.read_table(path)
            rows = table.filter(pc.equal(table["episode_index"], self.episode))
            if rows.num_rows:
                return {k: v[0] for k, v in rows.to_pydict().items()}
        raise IndexError(f"episode {self.episode} has no row in {self.root / 'meta' / 'episodes'}")

    def columns(self, names: Sequence[str]) -> dict[str, list]:
        """The episode's values of the data columns ``names`` (one entry per frame)."""
        missing = [n for n in names if n not in self._table]
        if missing:
            import pyarrow.compute as pc
            import pyarrow.parquet as pq

            path = self.root / self.info["data_path"].format(
                chunk_index=int(self.meta["data/chunk_index"]), file_index=int(self.meta["data/file_index"])
            )
            table = pq.read_table(path, columns=["episode_index", *missing])
            table = table.filter(pc.equal(table["episode_index"], self.episode))
            self._table.update({n: table[n].to_pylist() for n in missing})
        return {n: self._table[n] for n in names}

    def series(self, name: str) -> np.ndarray:
        """A numeric feature over the episode, ``(length, dim)`` float."""
        return np.asarray(self.columns([name])[name], dtype=np.float64).reshape(self.length, -1)

    def image_frames(self, name: str, indices: Sequence[int]) -> list[np.ndarray]:
        """Frames ``indices`` of the PNG image feature ``name`` as ``(H, W, 3)`` uint8."""
        from PIL import Image

        cells = self.columns([name])[name]
        return [np.asarray(Image.open(io.BytesIO(cells[i]["bytes"])).convert("RGB")) for i in indices]

    def video_frames(self, name: str, indices: Sequence[int]) -> list[np.ndarray]:
        """Frames ``indices`` of the video feature ``name`` as ``(H, W, 3)`` uint8 (one decoding pass)."""
        import av

        prefix = f"videos/{name}/"
        path = self.root / self.info["video_path"].format(
            video_key=name,
            chunk_index=int(self.meta[prefix + "chunk_index"]),
            file_index=int(self.meta[prefix + "file_index"]),
        )
        start = float(self.meta[prefix + "from_timestamp"])
        wanted, out = set(int(i) for i in indices), {}
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            stream.thread_type = "AUTO"
            time_base = stream.time_base
            if time_base is None:
                raise ValueError(f"{path} has a video stream without a time base ({name})")
            if start > 0:
                container.seek(int(start / time_base), stream=stream, backward=True)
            for frame in container.decode(stream):
                index = int(round((float(frame.pts * time_base) - start) * self.fps))
                if index in wanted:
                    out[index] = frame.to_ndarray(format="rgb24")
                if index >= max(wanted) or len(out) == len(wanted):
                    break
        missing = sorted(wanted - set(out))
        if missing:
            raise ValueError(f"{path} has no frame(s) {missing[:5]} of episode {self.episode} ({name})")
        return [out[int(i)] for i in indices]

    def camera_frames(self, name: str, indices: Sequence[int]) -> list[np.ndarray]:
        """Frames of an image or video feature (see :meth:`image_frames`, :meth:`video_frames`)."""
        if self.features[name]["dtype"] == "video":
            return self.video_frames(name, indices)
        return self.image_frames(name, indices)
