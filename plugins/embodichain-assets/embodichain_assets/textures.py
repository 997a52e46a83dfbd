"""Procedural stand-ins for the COCO photos of ``CocoBackground/coco`` (numpy only).

Eight kinds, cycled: checkerboard, stripes at a random angle, linear or radial gradient,
value-noise clouds, random circles and polygons, wood, marble, flat colour with grain. Texture
``i`` uses ``numpy.random.default_rng([SEED, i])``, so each image is reproducible on its own.

Example:
    >>> image = texture(3)  # (256, 256, 3) uint8
"""

from __future__ import annotations

from typing import Callable

import numpy as np

SEED = 20240611
SIZE = 256
COUNT = 32


def _grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre coordinates in [0, 1): ``(x, y)`` arrays of shape ``(size, size)``."""
    t = (np.arange(size) + 0.5) / size
    x, y = np.meshgrid(t, t)
    return x, y


def _colour(
    rng: np.random.Generator, sat: tuple[float, float] = (0.3, 0.9), val: tuple[float, float] = (0.3, 0.95)
) -> np.ndarray:
    """A random RGB colour in [0, 1] from a random hue, saturation and value."""
    h, s, v = rng.random(), rng.uniform(*sat), rng.uniform(*val)
    k = (np.array([5.0, 3.0, 1.0]) + h * 6.0) % 6.0
    return v - v * s * np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)


def _mix(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Per-pixel blend of colours ``a`` and ``b`` by ``t`` (``(H, W)`` in [0, 1])."""
    return a + (b - a) * np.clip(t, 0.0, 1.0)[..., None]


def value_noise(rng: np.random.Generator, size: int, cells: int) -> np.ndarray:
    """Smooth noise in [0, 1]: random lattice values, smoothstep-interpolated."""
    lattice = rng.random((cells + 1, cells + 1))
    t = np.arange(size) * cells / size
    i = t.astype(int)
    f = t - i
    f = f * f * (3.0 - 2.0 * f)
    rows = lattice[i] * (1 - f)[:, None] + lattice[i + 1] * f[:, None]
    return rows[:, i] * (1 - f)[None, :] + rows[:, i + 1] * f[None, :]


def fbm(rng: np.random.Generator, size: int, octaves: int = 5, base: int = 4) -> np.ndarray:
    """Fractal value noise normalised to [0, 1]."""
    total: np.ndarray = np.zeros((size, size))
    for o in range(octaves):
        total = total + value_noise(rng, size, base << o) * 0.5**o
    return (total - total.min()) / max(float(np.ptp(total)), 1e-9)


def _checker(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    n = int(rng.choice([4, 8, 16]))
    odd = ((np.floor(x * n) + np.floor(y * n)) % 2).astype(float)
    return _mix(_colour(rng), _colour(rng), odd)


def _stripes(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    angle = rng.uniform(0.0, np.pi)
    t = (x * np.cos(angle) + y * np.sin(angle)) * rng.uniform(4.0, 14.0)
    colours = [_colour(rng) for _ in range(int(rng.integers(2, 4)))]
    band = np.floor(t).astype(int) % len(colours)
    return np.stack(colours)[band]


def _gradient(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    if rng.random() < 0.5:
        angle = rng.uniform(0.0, 2.0 * np.pi)
        t = (x - 0.5) * np.cos(angle) + (y - 0.5) * np.sin(angle) + 0.5
    else:
        cx, cy = rng.uniform(0.2, 0.8, 2)
        t = np.hypot(x - cx, y - cy) / rng.uniform(0.5, 0.9)
    return _mix(_colour(rng), _colour(rng), t)


def _clouds(rng: np.random.Generator, size: int) -> np.ndarray:
    return _mix(_colour(rng, val=(0.5, 1.0)), _colour(rng), fbm(rng, size))


def _shapes(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    image = np.broadcast_to(_colour(rng), (size, size, 3)).copy()
    for _ in range(int(rng.integers(6, 13))):
        cx, cy, r = rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0.05, 0.25)
        sides = int(rng.integers(0, 7))
        if sides < 3:  # a circle
            inside = np.hypot(x - cx, y - cy) < r
        else:  # a regular polygon: inside every edge's half plane
            phase = rng.uniform(0, 2 * np.pi)
            angles = phase + 2 * np.pi * (np.arange(sides) + 0.5) / sides
            apothem = r * np.cos(np.pi / sides)
            inside = np.all([(x - cx) * np.cos(a) + (y - cy) * np.sin(a) < apothem for a in angles], axis=0)
        image[inside] = _colour(rng)
    return image


def _wood(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    cx, cy = rng.uniform(0.0, 1.0), rng.uniform(-1.2, -0.6)
    d = np.hypot((x - cx) * 3.0, y - cy) + 0.05 * fbm(rng, size)
    rings = (d * rng.uniform(5.0, 9.0)) % 1.0
    dark = np.array([0.35, 0.2, 0.1]) * rng.uniform(0.7, 1.1)
    light = np.array([0.8, 0.6, 0.38]) * rng.uniform(0.85, 1.15)
    return _mix(light, dark, rings**3)


def _marble(rng: np.random.Generator, size: int) -> np.ndarray:
    x, y = _grid(size)
    turbulence = fbm(rng, size, octaves=6)
    veins = 0.5 + 0.5 * np.sin((x + y * rng.uniform(0.3, 1.5)) * rng.uniform(8.0, 16.0) + 6.0 * turbulence)
    base = _colour(rng, sat=(0.0, 0.15), val=(0.8, 0.98))
    return _mix(base, _colour(rng, sat=(0.0, 0.4), val=(0.15, 0.5)), veins**6)


def _grain(rng: np.random.Generator, size: int) -> np.ndarray:
    noise = rng.normal(0.0, rng.uniform(0.01, 0.03), (size, size, 1))
    return _colour(rng) + noise


KINDS: list[tuple[str, Callable[[np.random.Generator, int], np.ndarray]]] = [
    ("checker", _checker),
    ("stripes", _stripes),
    ("gradient", _gradient),
    ("clouds", _clouds),
    ("shapes", _shapes),
    ("wood", _wood),
    ("marble", _marble),
    ("grain", _grain),
]


def texture(index: int, size: int = SIZE) -> np.ndarray:
    """Texture ``index`` as an ``(size, size, 3)`` uint8 RGB image."""
    rng = np.random.default_rng([SEED, index])
    image = KINDS[index % len(KINDS)][1](rng, size)
    return np.clip(np.rint(np.asarray(image, dtype=np.float64) * 255.0), 0, 255).astype(np.uint8)


def texture_name(index: int) -> str:
    """File name of texture ``index``: ``coco_000.png`` ..."""
    return f"coco_{index:03d}.png"
