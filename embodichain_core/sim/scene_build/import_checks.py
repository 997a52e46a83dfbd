"""Robustness of imported URDF/MJCF models: inertias, unreadable meshes.

* :func:`balance_inertias`: vendor URDFs often give link inertias that break MuJoCo's
  triangle inequality (principal moments ``A + B >= C``), which fails the compile. The
  offending links are found here, named in one :class:`ModelImportWarning`, and the
  model's compiler gets ``balanceinertia`` (MuJoCo then replaces those inertias by
  the closest valid ones; the other links keep theirs).
* :func:`explain_compile_error`: a mesh MuJoCo cannot read (a corrupt STL/OBJ file, or a
  missing one an MJCF names) fails the scene compile with MuJoCo's decoder message; it is re-raised as a
  ``ConfigError`` at the entity's ``fpath`` naming the file and the link(s) using it.
"""

from __future__ import annotations

import re
import warnings
from typing import Any, Mapping, Optional

import mujoco
import numpy as np

from embodichain_core.config.errors import ConfigError, join_path

_ELEMENT = re.compile(r"Element name '([^']*)'")


class ModelImportWarning(UserWarning):
    """An imported model was changed to load (balanced inertias, replaced actuators)."""


def principal_moments(body: Any) -> Optional[np.ndarray]:
    """Sorted principal moments of a spec body's explicit inertia (None if it has none)."""
    if not body.explicitinertial:
        return None
    full = np.asarray(body.fullinertia, dtype=float)
    if np.isfinite(full[0]):
        xx, yy, zz, xy, xz, yz = full
        matrix = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        return np.sort(np.linalg.eigvalsh(matrix))
    return np.sort(np.asarray(body.inertia, dtype=float))


def unbalanced_inertia_bodies(spec: mujoco.MjSpec) -> list[str]:
    """Bodies whose principal moments break ``A + B >= C`` (MuJoCo's compile check)."""
    out = []
    for body in spec.bodies:
        moments = principal_moments(body)
        if moments is None or moments[2] <= 0:
            continue
        if moments[0] + moments[1] < moments[2] * (1.0 - 1e-9):
            out.append(body.name)
    return out


def balance_inertias(spec: mujoco.MjSpec, owner: str) -> list[str]:
    """Turn on ``balanceinertia`` when some inertias break the triangle inequality.

    Args:
        spec: the articulation's own spec (its compiler settings apply to its bodies).
        owner: who the model belongs to, for the warning (``"robot 'arm'"``).

    Returns:
        The offending link names (one :class:`ModelImportWarning` names them).
    """
    bad = unbalanced_inertia_bodies(spec)
    if bad:
        spec.compiler.balanceinertia = True
        warnings.warn(
            f"{owner}: the inertias of link(s) {', '.join(repr(b) for b in bad)} break MuJoCo's "
            f"triangle inequality (A + B >= C); balanced with MuJoCo's balanceinertia",
            ModelImportWarning,
            stacklevel=4,
        )
    return bad


def mesh_users(spec: mujoco.MjSpec) -> dict[str, list[str]]:
    """Mesh name -> names of the bodies (links) whose geoms use it."""
    out: dict[str, list[str]] = {}
    for geom in spec.geoms:
        if geom.type == mujoco.mjtGeom.mjGEOM_MESH and geom.meshname:
            users = out.setdefault(geom.meshname, [])
            body = geom.parent.name
            if body not in users:
                users.append(body)
    return out


def explain_compile_error(err: Exception, spec: mujoco.MjSpec, paths: Mapping[str, str]) -> Optional[ConfigError]:
    """A ``ConfigError`` for a compile error caused by a mesh, else None.

    Args:
        err: MuJoCo's compile error (naming the element, ``Element name '<name>'``, or the file).
        spec: the scene spec that failed.
        paths: entity uid -> its config path (``{"robot": "robot"}``).
    """
    found = _ELEMENT.search(str(err))
    name = found.group(1) if found else None
    mesh = next((m for m in spec.meshes if m.name == name or (name is None and m.file and m.file in str(err))), None)
    if mesh is None:
        return None
    name = mesh.name
    links = mesh_users(spec).get(name, [])
    uid = name.split("/", 1)[0] if "/" in name else ""
    where = join_path(paths[uid], "fpath") if uid in paths else ""
    detail = str(err).splitlines()[0].removeprefix("Error: ")
    used = f"link(s) {', '.join(repr(link) for link in links)}" if links else "no link"
    return ConfigError(
        where, f"cannot read mesh file {mesh.file or '(inline)'!r} (mesh {name!r}, used by {used}): {detail}"
    )
