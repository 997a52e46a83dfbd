"""Small helpers to author robots with ``mujoco.MjSpec``: materials, primitive
geoms, joints and explicit inertias.

Every robot of this package is generated from Python numbers with these helpers
(no mesh files): coloured primitive shells over dark joint housings.

Example:
    >>> spec = new_spec("demo")
    >>> body = add_body(spec.worldbody, "base", mass=1.0, inertia_box=(0.1, 0.1, 0.1))
    >>> add_geom(body, "box", size=(0.05, 0.05, 0.05), colour="yellow")
"""

from __future__ import annotations

from typing import Iterable, Optional, Sequence

import mujoco
import numpy as np

#: Colour name -> RGBA of the shared materials (``mat_<name>``).
PALETTE: dict[str, tuple[float, float, float, float]] = {
    "yellow": (0.98, 0.72, 0.05, 1.0),
    "black": (0.09, 0.09, 0.10, 1.0),
    "grey": (0.34, 0.35, 0.37, 1.0),
    "silver": (0.72, 0.73, 0.75, 1.0),
    "white": (0.92, 0.92, 0.90, 1.0),
    "glass": (0.02, 0.05, 0.09, 1.0),
    "orange": (0.95, 0.45, 0.10, 1.0),
}

_GEOM_TYPES = {
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "ellipsoid": mujoco.mjtGeom.mjGEOM_ELLIPSOID,
}


def new_spec(name: str) -> mujoco.MjSpec:
    """An empty spec in radians with the palette's materials (``mat_<colour>``)."""
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    spec.compiler.autolimits = True
    for colour, rgba in PALETTE.items():
        mat = spec.add_material(name=f"mat_{colour}")
        mat.rgba = list(rgba)
        mat.specular = 0.35 if colour != "black" else 0.2
        mat.shininess = 0.4
    return spec


def add_body(
    parent: mujoco.MjsBody,
    name: str,
    pos: Sequence[float] = (0, 0, 0),
    quat: Sequence[float] = (1, 0, 0, 0),
    mass: float = 0.0,
    inertia_box: Optional[Sequence[float]] = None,
    ipos: Sequence[float] = (0, 0, 0),
) -> mujoco.MjsBody:
    """A child body with an explicit inertial.

    Args:
        parent: the parent body.
        name: body name.
        pos: position in the parent frame.
        quat: orientation (w, x, y, z) in the parent frame.
        mass: body mass; 0 leaves the body massless (only for bodies without joints).
        inertia_box: full extents (x, y, z) of the box whose inertia the body gets.
        ipos: centre of mass in the body frame.
    """
    body = parent.add_body(name=name, pos=list(pos), quat=list(quat))
    if mass > 0:
        ext = np.asarray(inertia_box if inertia_box is not None else (0.05, 0.05, 0.05), dtype=float)
        body.explicitinertial = True
        body.mass = float(mass)
        body.ipos = list(ipos)
        body.inertia = list(box_inertia(mass, ext))
    return body


def box_inertia(mass: float, extents: Iterable[float]) -> np.ndarray:
    """Principal inertia of a solid box of full ``extents`` (x, y, z)."""
    x, y, z = (float(v) for v in extents)
    return mass / 12.0 * np.array([y * y + z * z, x * x + z * z, x * x + y * y])


def add_geom(
    body: mujoco.MjsBody,
    kind: str,
    *,
    colour: str,
    size: Sequence[float] = (0, 0, 0),
    fromto: Optional[Sequence[float]] = None,
    pos: Sequence[float] = (0, 0, 0),
    quat: Sequence[float] = (1, 0, 0, 0),
    name: str = "",
    visual: bool = False,
) -> mujoco.MjsGeom:
    """A massless primitive geom (masses come from the body's explicit inertial).

    Args:
        body: owner body.
        kind: ``box``, ``capsule``, ``cylinder``, ``sphere`` or ``ellipsoid``.
        colour: a :data:`PALETTE` name.
        size: MuJoCo size (half extents / radius, half length).
        fromto: segment end points for capsules and cylinders (overrides pos/quat).
        pos: centre in the body frame.
        quat: orientation in the body frame.
        name: optional geom name.
        visual: True for decoration that never collides.
    """
    size = list(size) + [0.0] * (3 - len(size))
    geom = body.add_geom(
        type=_GEOM_TYPES[kind],
        size=size,
        pos=list(pos),
        quat=list(quat),
        material=f"mat_{colour}",
        rgba=list(PALETTE[colour]),
    )
    if name:
        geom.name = name
    if fromto is not None:
        geom.fromto = list(fromto)
    geom.mass = 0.0
    if visual:
        geom.contype, geom.conaffinity, geom.group = 0, 0, 1
    return geom


def add_hinge(
    body: mujoco.MjsBody,
    name: str,
    axis: Sequence[float],
    limits: Sequence[float],
    armature: float = 0.0,
    damping: float = 0.0,
    pos: Sequence[float] = (0, 0, 0),
) -> mujoco.MjsJoint:
    """A limited hinge joint (``limits`` in radians)."""
    return body.add_joint(
        name=name,
        type=mujoco.mjtJoint.mjJNT_HINGE,
        axis=list(axis),
        pos=list(pos),
        range=[float(limits[0]), float(limits[1])],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        armature=float(armature),
        damping=float(damping),
    )


def add_slide(
    body: mujoco.MjsBody,
    name: str,
    axis: Sequence[float],
    limits: Sequence[float],
    armature: float = 0.0,
    damping: float = 0.0,
) -> mujoco.MjsJoint:
    """A limited prismatic joint (``limits`` in metres)."""
    return body.add_joint(
        name=name,
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=list(axis),
        range=[float(limits[0]), float(limits[1])],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        armature=float(armature),
        damping=float(damping),
    )


def add_mimic(spec: mujoco.MjSpec, follower: str, leader: str, multiplier: float = 1.0, offset: float = 0.0) -> None:
    """``follower = offset + multiplier * leader`` as a stiff joint equality."""
    eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=follower, name2=leader)
    eq.name = f"mimic_{follower}"
    eq.data = np.array([offset, multiplier, 0.0, 0.0, 0.0] + [0.0] * (len(eq.data) - 5))
    eq.solref = [0.005, 1.0]


def axis_quat(axis: str) -> list[float]:
    """Quaternion turning a geom's local z axis onto ``axis`` (``"x"`` or ``"y"``)."""
    s = float(np.sqrt(0.5))
    return {"x": [s, 0.0, s, 0.0], "y": [s, -s, 0.0, 0.0], "z": [1.0, 0.0, 0.0, 0.0]}[axis]
