"""A minimal line-plot PNG writer (numpy + zlib) for learning curves.

Used when matplotlib is not installed: axes with numbered ticks, a title, axis
labels and one or more polylines, drawn with a built-in 5x7 bitmap font.

Example:
    >>> import numpy as np
    >>> png = line_plot_png([np.arange(5)], [np.arange(5) ** 2], title="SQUARES")
    >>> png[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
    True
"""

from __future__ import annotations

import math
import struct
import zlib
from typing import Optional, Sequence, Union

import numpy as np

__all__ = ["line_plot_png", "encode_png", "COLORS"]

Series = Union[Sequence[float], np.ndarray]
"""The values of one line: a sequence of numbers or a 1-d array."""

#: Line colours (RGB) of successive series.
COLORS = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40))

# 5x7 glyphs: each row is 5 bits, most significant bit on the left.
_FONT = {
    "0": (14, 17, 19, 21, 25, 17, 14),
    "1": (4, 12, 4, 4, 4, 4, 14),
    "2": (14, 17, 1, 2, 4, 8, 31),
    "3": (30, 1, 1, 14, 1, 1, 30),
    "4": (2, 6, 10, 18, 31, 2, 2),
    "5": (31, 16, 30, 1, 1, 17, 14),
    "6": (6, 8, 16, 30, 17, 17, 14),
    "7": (31, 1, 2, 4, 8, 8, 8),
    "8": (14, 17, 17, 14, 17, 17, 14),
    "9": (14, 17, 17, 15, 1, 2, 12),
    ".": (0, 0, 0, 0, 0, 12, 12),
    "-": (0, 0, 0, 31, 0, 0, 0),
    "+": (0, 4, 4, 31, 4, 4, 0),
    "(": (2, 4, 8, 8, 8, 4, 2),
    ")": (8, 4, 2, 2, 2, 4, 8),
    "/": (1, 1, 2, 4, 8, 16, 16),
    ":": (0, 12, 12, 0, 12, 12, 0),
    ",": (0, 0, 0, 0, 12, 4, 8),
    "=": (0, 0, 31, 0, 31, 0, 0),
    "%": (24, 25, 2, 4, 8, 19, 3),
    "_": (0, 0, 0, 0, 0, 0, 31),
    " ": (0,) * 7,
    "A": (14, 17, 17, 31, 17, 17, 17),
    "B": (30, 17, 17, 30, 17, 17, 30),
    "C": (14, 17, 16, 16, 16, 17, 14),
    "D": (30, 17, 17, 17, 17, 17, 30),
    "E": (31, 16, 16, 30, 16, 16, 31),
    "F": (31, 16, 16, 30, 16, 16, 16),
    "G": (14, 17, 16, 23, 17, 17, 15),
    "H": (17, 17, 17, 31, 17, 17, 17),
    "I": (14, 4, 4, 4, 4, 4, 14),
    "J": (7, 2, 2, 2, 2, 18, 12),
    "K": (17, 18, 20, 24, 20, 18, 17),
    "L": (16, 16, 16, 16, 16, 16, 31),
    "M": (17, 27, 21, 21, 17, 17, 17),
    "N": (17, 17, 25, 21, 19, 17, 17),
    "O": (14, 17, 17, 17, 17, 17, 14),
    "P": (30, 17, 17, 30, 16, 16, 16),
    "Q": (14, 17, 17, 17, 21, 18, 13),
    "R": (30, 17, 17, 30, 20, 18, 17),
    "S": (15, 16, 16, 14, 1, 1, 30),
    "T": (31, 4, 4, 4, 4, 4, 4),
    "U": (17, 17, 17, 17, 17, 17, 14),
    "V": (17, 17, 17, 17, 17, 10, 4),
    "W": (17, 17, 17, 21, 21, 21, 10),
    "X": (17, 17, 10, 4, 10, 17, 17),
    "Y": (17, 17, 10, 4, 4, 4, 4),
    "Z": (31, 1, 2, 4, 8, 16, 31),
}


def encode_png(image: np.ndarray) -> bytes:
    """Encode an (H, W, 3) uint8 RGB image as PNG bytes."""
    height, width, _ = image.shape
    raw = b"".join(b"\x00" + image[row].tobytes() for row in range(height))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def _text(
    img: np.ndarray, x: int, y: int, text: str, scale: int = 2, color: tuple = (0, 0, 0), vertical: bool = False
) -> None:
    """Draw ``text`` (upper-cased) with its top-left corner at ``(x, y)``."""
    for i, char in enumerate(text.upper()):
        rows = _FONT.get(char, _FONT[" "])
        for r, bits in enumerate(rows):
            for c in range(5):
                if not bits >> (4 - c) & 1:
                    continue
                dx, dy = (r, -(i * 6 + c)) if vertical else (i * 6 + c, r)
                x0, y0 = x + dx * scale, y + dy * scale
                if 0 <= y0 and y0 + scale <= img.shape[0] and 0 <= x0 and x0 + scale <= img.shape[1]:
                    img[y0 : y0 + scale, x0 : x0 + scale] = color


def _line(img: np.ndarray, p0: tuple, p1: tuple, color: tuple, width: int = 2) -> None:
    """A line of ``width`` pixels from ``p0`` to ``p1`` (pixel coordinates)."""
    n = int(max(abs(p1[0] - p0[0]), abs(p1[1] - p0[1]))) + 1
    xs = np.linspace(p0[0], p1[0], n).round().astype(int)
    ys = np.linspace(p0[1], p1[1], n).round().astype(int)
    for dx in range(-(width // 2), width - width // 2):
        for dy in range(-(width // 2), width - width // 2):
            x, y = np.clip(xs + dx, 0, img.shape[1] - 1), np.clip(ys + dy, 0, img.shape[0] - 1)
            img[y, x] = color


def _ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """About ``count`` round tick values covering ``[lo, hi]``."""
    span = hi - lo if hi > lo else 1.0
    raw = span / count
    step = 10 ** math.floor(math.log10(raw))
    step *= next(m for m in (1, 2, 5, 10) if raw <= m * step)
    start = math.ceil(lo / step) * step
    return [start + i * step for i in range(int((hi - start) / step + 1e-9) + 1)]


def _fmt(value: float) -> str:
    if abs(value) >= 10000:
        return f"{value / 1000:g}K"
    return f"{value:.4g}"


def line_plot_png(
    xs: Sequence[Series],
    ys: Sequence[Series],
    title: str = "",
    xlabel: str = "",
    ylabel: str = "",
    labels: Optional[Sequence[str]] = None,
    size: tuple[int, int] = (900, 560),
) -> bytes:
    """Render series ``(xs[i], ys[i])`` as a line plot; return PNG bytes."""
    width, height = size
    img = np.full((height, width, 3), 255, dtype=np.uint8)
    left, right, top, bottom = 110, width - 30, 50, height - 70
    all_x = np.concatenate([np.asarray(x, float) for x in xs])
    all_y = np.concatenate([np.asarray(y, float) for y in ys])
    x_lo, x_hi = float(all_x.min()), float(all_x.max()) or 1.0
    pad = 0.05 * (float(all_y.max()) - float(all_y.min()) or 1.0)
    y_lo, y_hi = float(all_y.min()) - pad, float(all_y.max()) + pad

    def px(x: float, y: float) -> tuple[float, float]:
        fx = (x - x_lo) / (x_hi - x_lo or 1.0)
        fy = (y - y_lo) / (y_hi - y_lo or 1.0)
        return left + fx * (right - left), bottom - fy * (bottom - top)

    for value in _ticks(y_lo, y_hi):
        y = int(px(x_lo, value)[1])
        _line(img, (left, y), (right, y), (225, 225, 225), 1)
        _text(img, left - 12 - 12 * len(_fmt(value)), y - 7, _fmt(value))
    for value in _ticks(x_lo, x_hi):
        x = int(px(value, y_lo)[0])
        _line(img, (x, bottom), (x, bottom + 6), (0, 0, 0), 2)
        _text(img, x - 6 * len(_fmt(value)), bottom + 12, _fmt(value))
    _line(img, (left, top), (left, bottom), (0, 0, 0), 2)
    _line(img, (left, bottom), (right, bottom), (0, 0, 0), 2)
    for i, (x_values, y_values) in enumerate(zip(xs, ys)):
        points = [px(x, y) for x, y in zip(x_values, y_values)]
        for p0, p1 in zip(points, points[1:]):
            _line(img, p0, p1, COLORS[i % len(COLORS)], 3)
        if labels:
            _line(img, (left + 20, top + 12 + 22 * i), (left + 50, top + 12 + 22 * i), COLORS[i % len(COLORS)], 3)
            _text(img, left + 58, top + 5 + 22 * i, labels[i])
    _text(img, (width - 12 * len(title)) // 2, 15, title)
    _text(img, (left + right - 12 * len(xlabel)) // 2, height - 30, xlabel)
    _text(img, 15, (top + bottom + 12 * len(ylabel)) // 2, ylabel, vertical=True)
    return encode_png(img)
