"""Previews of a recorded episode: its camera streams and its state/action curves.

* cameras: a contact sheet PNG (rows: camera streams, depth maps (normalised per
  row, black: nothing in range) and masks (one colour per entity); columns: frames
  sampled evenly over the episode) or an mp4 of all streams side by side;
* ``state_action.png``: ``observation.state`` and ``action`` over time (matplotlib:
  one panel each, time axis in seconds, one labelled line per joint).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
from PIL import Image, ImageDraw

from embodichain_lerobot.episode_reader import EpisodeFiles
from embodichain_lerobot.packing import DEPTH_MAX_MM, mask_ids, unpack_u16

_MIN_TILE = 96


def _to_hwc_uint8(value: Any) -> np.ndarray:
    """A camera item (``(C, H, W)`` float in [0, 1]) or a depth map as ``(H, W, 3)`` uint8."""
    arr = np.asarray(value.detach().cpu().numpy() if hasattr(value, "detach") else value)  # a tensor on any device
    if arr.ndim == 3 and arr.shape[0] in (1, 3) and arr.shape[-1] not in (1, 3):
        arr = arr.transpose(1, 2, 0)
    if arr.ndim == 2:
        arr = arr[..., None]
    if arr.dtype != np.uint8:
        arr = (np.clip(arr, 0.0, 1.0) * 255 + 0.5).astype(np.uint8)
    return np.repeat(arr, 3, axis=-1) if arr.shape[-1] == 1 else arr[..., :3]


def _is_map(shape: Sequence[int]) -> bool:
    return len(shape) == 2 or (len(shape) == 3 and shape[-1] == 1)


def preview_streams(features: dict[str, dict]) -> list[str]:
    """The previewed features: colour, depth and mask images/videos, and raw depth maps."""
    out = []
    for name, ft in features.items():
        if ft["dtype"] in ("image", "video") or (name.startswith("observation.depth.") and _is_map(ft["shape"])):
            out.append(name)
    return out


def _normalised(maps: list[np.ndarray]) -> list[np.ndarray]:
    stack = np.stack(maps).astype(np.float32) if maps else np.zeros((0, 1, 1), np.float32)
    lo, hi = (float(stack.min()), float(stack.max())) if stack.size else (0.0, 1.0)
    return [_to_hwc_uint8((m - lo) / (hi - lo if hi > lo else 1.0)) for m in stack]


def _colour_ids(ids: np.ndarray) -> np.ndarray:
    """Entity ids as distinct colours (black: no entity)."""
    rng = np.random.default_rng(7)
    palette = np.concatenate([np.zeros((1, 3), np.uint8), rng.integers(60, 256, (int(ids.max()) + 1, 3), np.uint8)])
    return palette[ids + 1]


def collect_streams(ep: EpisodeFiles, indices: Sequence[int]) -> dict[str, list[np.ndarray]]:
    """``{stream: [(H, W, 3) uint8 per index]}``: colour as stored, depth normalised, masks coloured."""
    out: dict[str, list[np.ndarray]] = {}
    for name in preview_streams(ep.features):
        if ep.features[name]["dtype"] not in ("image", "video"):  # raw depth (depth_format "raw")
            cells = ep.columns([name])[name]
            out[name] = _normalised(
                [np.asarray(cells[i], np.float32).reshape(ep.features[name]["shape"][:2]) for i in indices]
            )
            continue
        frames = ep.camera_frames(name, indices)
        if name.startswith("observation.depth."):
            far = [np.where(m == DEPTH_MAX_MM, 0, m) for m in (unpack_u16(f) for f in frames)]
            out[name] = _normalised(far)
        elif name.startswith("observation.mask."):
            out[name] = [_colour_ids(mask_ids(f)) for f in frames]
        else:
            out[name] = frames
    return out


def _tile(img: np.ndarray) -> Image.Image:
    pil = Image.fromarray(img)
    scale = max(1, -(-_MIN_TILE // max(1, img.shape[0])))
    return pil.resize((pil.width * scale, pil.height * scale), Image.Resampling.NEAREST) if scale > 1 else pil


def contact_sheet(streams: dict[str, list[np.ndarray]], labels: Sequence[str], path: Path) -> Path:
    """Rows = streams, columns = sampled frames, with a text header; saved as PNG."""
    rows = [[_tile(img) for img in imgs] for imgs in streams.values()]
    tw = max((t.width for r in rows for t in r), default=_MIN_TILE)
    th = max((t.height for r in rows for t in r), default=_MIN_TILE)
    pad, head, left = 4, 16, 200
    sheet = Image.new("RGB", (left + len(labels) * (tw + pad), head + len(rows) * (th + head)), "white")
    draw = ImageDraw.Draw(sheet)
    for c, label in enumerate(labels):
        draw.text((left + c * (tw + pad), 2), label, fill="black")
    for r, (name, tiles) in enumerate(zip(streams, rows)):
        y = head + r * (th + head)
        draw.text((4, y + th // 2), name, fill="black")
        for c, tile in enumerate(tiles):
            sheet.paste(tile, (left + c * (tw + pad), y))
    sheet.save(path)
    return path


def write_mp4(streams: dict[str, list[np.ndarray]], fps: int, path: Path) -> Path:
    """All streams side by side per frame, encoded with PyAV (H.264, else MPEG-4).

    FFmpeg's own messages below errors are off: x264 prints a dozen lines of statistics per
    video at its default level once lerobot's video helpers have restored FFmpeg's default log
    callback, which would break ``--quiet`` (``eval-policy --video``, ``dataset preview``).
    """
    import av
    import av.logging

    av.logging.set_libav_level(av.logging.ERROR)

    frames = [
        np.concatenate([np.asarray(_tile(s[t])) for s in streams.values()], axis=1)
        for t in range(len(next(iter(streams.values()))))
    ]
    h, w = frames[0].shape[:2]
    with av.open(str(path), mode="w") as container:
        codec = "libx264" if "libx264" in av.codecs_available else "mpeg4"
        stream = container.add_stream(codec, rate=int(fps))
        if not isinstance(stream, av.VideoStream):  # a video codec name always gives a video stream
            raise TypeError(f"codec {codec!r} opened a {type(stream).__name__}, not a video stream")
        stream.width, stream.height, stream.pix_fmt = w + w % 2, h + h % 2, "yuv420p"
        for img in frames:
            img = np.pad(img, ((0, h % 2), (0, w % 2), (0, 0)))
            container.mux(stream.encode(av.VideoFrame.from_ndarray(img, format="rgb24")))
        container.mux(stream.encode())
    return path


def _series(ds: Any, key: str) -> Optional[np.ndarray]:
    if key not in ds.features:
        return None
    if isinstance(ds, EpisodeFiles):
        return ds.series(key)
    import torch

    return torch.stack(list(ds.hf_dataset[key])).numpy().reshape(len(ds), -1)


def plot_state_action(ds: Any, path: Path, title: str) -> Path:
    """``observation.state`` and ``action`` over time, drawn with matplotlib.

    ``ds`` is an :class:`~embodichain_lerobot.episode_reader.EpisodeFiles` or a ``LeRobotDataset``.
    """
    n = ds.length if isinstance(ds, EpisodeFiles) else len(ds)
    t = np.arange(n) / float(ds.fps)
    series = {k: v for k in ("observation.state", "action") if (v := _series(ds, k)) is not None}
    names = {k: ds.features[k].get("names") for k in series}
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(series), 1, figsize=(9, 3 * len(series)), sharex=True, squeeze=False)
    for ax, (key, values) in zip(axes[:, 0], series.items()):
        labels = names[key] if isinstance(names[key], list) else [f"{key}[{i}]" for i in range(values.shape[1])]
        for i in range(values.shape[1]):
            ax.plot(t, values[:, i], label=str(labels[i]) if i < len(labels) else str(i))
        ax.set_ylabel(key)
        ax.legend(fontsize=7, ncol=4, loc="upper right")
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def preview_episode(
    path: str | Path, episode: int, out_dir: str | Path, fmt: str = "png", num_frames: int = 8
) -> list[Path]:
    """Write the camera preview (``fmt``: ``png`` or ``mp4``) and the state/action plot.

    The episode's files are read directly (:class:`~embodichain_lerobot.episode_reader.EpisodeFiles`),
    without importing lerobot.

    Raises:
        IndexError: no such episode.
    """
    ep = EpisodeFiles(path, episode)
    root, out = ep.root, Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{root.name}_ep{episode:03d}"
    written = [plot_state_action(ep, out / f"{stem}_state_action.png", f"{root.name} episode {episode}")]
    n = ep.length
    if fmt == "mp4":
        streams = collect_streams(ep, range(n))
        if streams:
            written.insert(0, write_mp4(streams, ep.fps, out / f"{stem}_cameras.mp4"))
        return written
    idx = sorted({int(round(x)) for x in np.linspace(0, n - 1, min(num_frames, n))})
    streams = collect_streams(ep, idx)
    if streams:
        labels = [f"t={i / float(ep.fps):.2f}s (frame {i})" for i in idx]
        written.insert(0, contact_sheet(streams, labels, out / f"{stem}_cameras.png"))
    return written
