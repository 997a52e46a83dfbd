"""Closed, outward-oriented triangle meshes of simple solids, and their union as one mesh.

Every function returns a :class:`Part`: a closed mesh whose faces wind counter-clockwise seen
from outside. Boxes and surfaces of revolution with a concave radius profile are convex; an
asset made of several parts keeps each part as its own connected component (parts overlap but
never share a vertex position), which is what lets the loader use one convex collision geom per
part without any decomposition.

Example:
    >>> top = box((0, 0, 0.78), (0.6, 0.5, 0.04))
    >>> leg = box((0.26, 0.21, 0.38), (0.04, 0.04, 0.76))
    >>> table = union([top, leg])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

# corner k of a box has x, y, z signs from the bits of k (bit 0: x, bit 1: y, bit 2: z)
_BOX_FACES = np.array(
    [
        [0, 2, 1],
        [1, 2, 3],  # -z
        [4, 5, 6],
        [5, 7, 6],  # +z
        [0, 1, 4],
        [1, 5, 4],  # -y
        [2, 6, 3],
        [3, 6, 7],  # +y
        [0, 4, 2],
        [2, 4, 6],  # -x
        [1, 3, 5],
        [3, 7, 5],  # +x
    ]
)


@dataclass
class Part:
    """A closed triangle mesh: ``vertices`` ``(V, 3)`` float64, ``faces`` ``(F, 3)`` int64."""

    vertices: np.ndarray
    faces: np.ndarray

    def transformed(self, rotation: np.ndarray | None = None, offset: Sequence[float] = (0, 0, 0)) -> "Part":
        """The part rotated by ``rotation`` (3x3, about the origin) then moved by ``offset``."""
        v = self.vertices if rotation is None else self.vertices @ np.asarray(rotation, float).T
        return Part(v + np.asarray(offset, dtype=float), self.faces.copy())


def rot_x(deg: float) -> np.ndarray:
    """Rotation matrix about +X by ``deg`` degrees."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(deg: float) -> np.ndarray:
    """Rotation matrix about +Y by ``deg`` degrees."""
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def box(center: Sequence[float], size: Sequence[float], rotation: np.ndarray | None = None) -> Part:
    """An (optionally rotated) box with full extents ``size`` centred at ``center``."""
    bits = (np.arange(8)[:, None] >> np.arange(3)) & 1
    local = (bits - 0.5) * np.asarray(size, dtype=float)
    return Part(local, _BOX_FACES.copy()).transformed(rotation, center)


def revolve(profile: Sequence[tuple[float, float]], segments: int = 48) -> Part:
    """A solid of revolution about +Z from a ``(radius, z)`` profile, bottom to top.

    The first and last profile points are closed with a centre vertex (a flat cap) when their
    radius is positive. The solid is convex when the radius is a concave function of ``z``.
    """
    prof = np.asarray(profile, dtype=float)
    angles = 2.0 * np.pi * np.arange(segments) / segments
    ring = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    verts = [np.column_stack([r * ring, np.full(segments, z)]) for r, z in prof]
    vertices = np.concatenate(verts + [[[0.0, 0.0, prof[0, 1]]], [[0.0, 0.0, prof[-1, 1]]]])
    bottom, top = len(prof) * segments, len(prof) * segments + 1
    j = np.arange(segments)
    k = (j + 1) % segments
    faces = []
    for i in range(len(prof) - 1):
        a, b = i * segments + j, (i + 1) * segments + j
        c, d = i * segments + k, (i + 1) * segments + k
        faces += [np.column_stack([a, c, d]), np.column_stack([a, d, b])]
    faces.append(np.column_stack([np.full(segments, bottom), k, j]))
    last = (len(prof) - 1) * segments
    faces.append(np.column_stack([np.full(segments, top), last + j, last + k]))
    return Part(vertices, np.concatenate(faces))


def cylinder(radius: float, z0: float, z1: float, segments: int = 48) -> Part:
    """A solid cylinder about +Z from ``z0`` to ``z1``."""
    return revolve([(radius, z0), (radius, z1)], segments)


def tube_arc(
    major: float, minor: float, start_deg: float, stop_deg: float, segments: int = 24, sides: int = 16
) -> Part:
    """A circular tube (radius ``minor``) swept along an arc of radius ``major`` in the XZ plane.

    The arc is centred at the origin and runs from ``start_deg`` to ``stop_deg`` (0 deg on +X,
    90 deg on +Z); both ends are capped, so the part is closed. It is not convex.
    """
    t = np.radians(np.linspace(start_deg, stop_deg, segments + 1))
    phi = 2.0 * np.pi * np.arange(sides) / sides
    centre = np.stack([major * np.cos(t), np.zeros_like(t), major * np.sin(t)], axis=1)
    radial = np.stack([np.cos(t), np.zeros_like(t), np.sin(t)], axis=1)
    out = np.array([0.0, 1.0, 0.0])
    ring = np.cos(phi)[None, :, None] * radial[:, None, :] + np.sin(phi)[None, :, None] * out
    vertices = (centre[:, None, :] + minor * ring).reshape(-1, 3)
    j = np.arange(sides)
    k = (j + 1) % sides
    faces = []
    for i in range(segments):
        a, b, c, d = i * sides + j, (i + 1) * sides + j, i * sides + k, (i + 1) * sides + k
        faces += [np.column_stack([a, d, b]), np.column_stack([a, c, d])]
    first, last = len(vertices), len(vertices) + 1
    vertices = np.concatenate([vertices, centre[:1], centre[-1:]])
    faces.append(np.column_stack([np.full(sides, first), k, j]))
    end = segments * sides
    faces.append(np.column_stack([np.full(sides, last), end + j, end + k]))
    return Part(vertices, np.concatenate(faces))


def union(parts: Sequence[Part]) -> Part:
    """All parts in one mesh (concatenated; each stays its own connected component)."""
    vertices, faces, offset = [], [], 0
    for part in parts:
        vertices.append(part.vertices)
        faces.append(part.faces + offset)
        offset += len(part.vertices)
    return Part(np.concatenate(vertices), np.concatenate(faces))
