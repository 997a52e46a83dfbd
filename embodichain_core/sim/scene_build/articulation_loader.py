"""Load URDF and MJCF articulations into a self-contained ``mujoco.MjSpec``.

The returned spec can be attached into a scene spec (``frame.attach_body(spec.worldbody
.first_body(), prefix, "")`` or ``scene.attach(spec, frame=frame, prefix=prefix)``): every asset
file path is made absolute, so nothing depends on the working directory or on the parent's
``meshdir``, and meshes MuJoCo cannot decode (PLY, GLB, glTF, DAE) are loaded with
:mod:`embodichain_core.sim.scene_build.mesh` and stored in the spec as user vertices and faces.

URDF specifics:

* ``<mujoco><compiler fusestatic="false" discardvisual="false" strippath="false"/></mujoco>`` is
  inserted when absent, so fixed links (``handle_xpos``) stay bodies whose frames can be queried,
  and visual meshes are kept (as non-colliding geoms in group 1);
* ``package://pkg/rel`` is looked up in the URDF folder and its parents (``<dir>/pkg/rel`` and
  ``<dir>/rel``); other relative paths are relative to the URDF file;
* ``<limit lower upper effort>`` becomes the joint range (limited) and the actuator force range,
  ``<dynamics damping friction>`` becomes joint damping and frictionloss, ``<mimic>`` becomes a
  joint equality (all done by MuJoCo's importer; the range is marked limited explicitly here).

Example:
    >>> spec = load_articulation_spec("SlidingBoxDrawer/SlidingBoxDrawer.urdf")  # doctest: +SKIP
    >>> list_joints(spec)  # doctest: +SKIP
    [JointInfo(name='slide_rails', type='slide', range=(0.0, 0.2))]
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import Any, NamedTuple

import mujoco

from embodichain_core.sim.scene_build.mesh import MUJOCO_NATIVE_SUFFIXES, load_mesh, set_user_mesh

URDF_COMPILER_DEFAULTS = {"fusestatic": "false", "discardvisual": "false"}
_PACKAGE_SEARCH_LEVELS = 8
_JOINT_TYPES = {
    mujoco.mjtJoint.mjJNT_FREE: "free",
    mujoco.mjtJoint.mjJNT_BALL: "ball",
    mujoco.mjtJoint.mjJNT_SLIDE: "slide",
    mujoco.mjtJoint.mjJNT_HINGE: "hinge",
}


class JointInfo(NamedTuple):
    """A joint of a spec: name, type (``hinge``/``slide``/``ball``/``free``), range or None."""

    name: str
    type: str
    range: tuple[float, float] | None


def load_articulation_spec(path: str | os.PathLike[str], inline_meshes: bool = False) -> mujoco.MjSpec:
    """Load a ``.urdf`` or ``.xml``/``.mjcf`` file into a self-contained ``MjSpec``.

    Args:
        path: the model file.
        inline_meshes: store every mesh as user vertices/faces, not only the formats MuJoCo
            cannot decode (makes ``spec.to_xml()`` independent of any file).

    Raises:
        FileNotFoundError: the file, or a mesh it references, does not exist (a URDF's
            message names the link).
        ValueError: unknown extension, or MuJoCo rejects the model.
    """
    path = os.path.abspath(os.fspath(path))
    if not os.path.isfile(path):
        raise FileNotFoundError(f"articulation file {path!r} does not exist")
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".urdf":
        spec = _load_urdf(path)
    elif suffix in (".xml", ".mjcf"):
        spec = mujoco.MjSpec.from_file(path)
        _absolutize_assets(spec)
    else:
        raise ValueError(f"{path}: expected a .urdf, .xml or .mjcf file, got {suffix!r}")
    _inline_meshes(spec, everything=inline_meshes)
    return spec


def _load_urdf(path: str) -> mujoco.MjSpec:
    """Parse a URDF after :func:`prepare_urdf`, and mark joints with a range as limited."""
    with open(path, encoding="utf-8") as handle:
        text = prepare_urdf(handle.read(), os.path.dirname(path))
    spec = mujoco.MjSpec.from_string(text)
    spec.modelfiledir = os.path.dirname(path) + os.sep
    for joint in spec.joints:
        if joint.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE) and joint.range[0] < joint.range[1]:
            joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    return spec


def prepare_urdf(text: str, base_dir: str) -> str:
    """URDF text with the MuJoCo compiler block ensured and mesh paths made absolute.

    Args:
        text: URDF XML.
        base_dir: the folder relative mesh paths are relative to (the URDF's folder).
    """
    root = ET.fromstring(text)
    if root.tag != "robot":
        raise ValueError(f"not a URDF: root element is <{root.tag}>, expected <robot>")
    compiler = _ensure_compiler(root)
    mesh_base = os.path.join(base_dir, compiler.attrib.pop("meshdir", ""))
    for link in root.iter("link"):
        for mesh in link.iter("mesh"):
            if not mesh.get("filename"):
                continue
            try:
                mesh.set("filename", resolve_mesh_path(mesh.get("filename", ""), mesh_base))
            except FileNotFoundError as err:
                raise FileNotFoundError(f"link {link.get('name')!r}: {err}") from None
    return ET.tostring(root, encoding="unicode")


def _ensure_compiler(root: ET.Element) -> ET.Element:
    """The ``<mujoco><compiler>`` element of a URDF, created or completed."""
    block = root.find("mujoco")
    if block is None:
        block = ET.Element("mujoco")
        root.insert(0, block)
    compiler = block.find("compiler")
    if compiler is None:
        compiler = ET.SubElement(block, "compiler")
    for key, value in URDF_COMPILER_DEFAULTS.items():
        compiler.attrib.setdefault(key, value)
    compiler.set("strippath", "false")  # paths are absolute from here on
    return compiler


def resolve_mesh_path(filename: str, base_dir: str) -> str:
    """Absolute path of a URDF mesh ``filename`` (``package://``, ``file://`` or relative).

    Raises:
        FileNotFoundError: no candidate exists (the message lists those tried).
    """
    name = filename[len("file://") :] if filename.startswith("file://") else filename
    base_dir = os.path.abspath(base_dir)
    if name.startswith("package://"):
        rel = name[len("package://") :]
        rest = rel.partition("/")[2]
        candidates = []
        folder = base_dir
        for _ in range(_PACKAGE_SEARCH_LEVELS):
            candidates += [os.path.join(folder, rel), os.path.join(folder, rest)]
            if os.path.dirname(folder) == folder:
                break
            folder = os.path.dirname(folder)
    else:
        candidates = [os.path.join(base_dir, os.path.expanduser(name))]
    for candidate in candidates:
        if os.path.isfile(candidate):
            return os.path.normpath(candidate)
    tried = "\n".join(f"  - {c}" for c in dict.fromkeys(candidates))
    raise FileNotFoundError(f"mesh {filename!r} not found; tried:\n{tried}")


def urdf_mesh_files(path: str | os.PathLike[str]) -> list[str]:
    """Absolute paths of the distinct mesh files a URDF references, in document order."""
    path = os.fspath(path)
    with open(path, encoding="utf-8") as handle:
        root = ET.fromstring(handle.read())
    base = os.path.dirname(os.path.abspath(path))
    files = [resolve_mesh_path(m.get("filename", ""), base) for m in root.iter("mesh") if m.get("filename")]
    return list(dict.fromkeys(files))


def _absolutize_assets(spec: mujoco.MjSpec) -> None:
    """Make mesh, skin, height-field and texture file paths of an MJCF spec absolute."""
    base = spec.modelfiledir or os.getcwd()
    mesh_dir = os.path.join(base, spec.meshdir or "")
    texture_dir = os.path.join(base, spec.texturedir or "")
    for element in [*spec.meshes, *spec.skins, *spec.hfields]:
        if element.file and not os.path.isabs(element.file):
            element.file = os.path.normpath(os.path.join(mesh_dir, element.file))
    for texture in spec.textures:
        if texture.file and not os.path.isabs(texture.file):
            texture.file = os.path.normpath(os.path.join(texture_dir, texture.file))
        cube = list(texture.cubefiles)
        if any(cube):
            texture.cubefiles = [os.path.normpath(os.path.join(texture_dir, f)) if f else f for f in cube]


def _inline_meshes(spec: mujoco.MjSpec, everything: bool = False) -> None:
    """Replace file meshes MuJoCo cannot decode (or all, with ``everything``) by user meshes.

    Raises:
        FileNotFoundError / ValueError: a missing or unreadable file (naming it and its links).
    """
    from embodichain_core.sim.scene_build.import_checks import mesh_users

    for mesh in spec.meshes:
        suffix = os.path.splitext(mesh.file)[1].lower()
        if mesh.file and (everything or suffix not in MUJOCO_NATIVE_SUFFIXES):
            if suffix == ".msh":
                continue  # MuJoCo's own binary format; only MuJoCo reads it
            links = ", ".join(repr(b) for b in mesh_users(spec).get(mesh.name, [])) or "no link"
            if not os.path.isfile(mesh.file):
                raise FileNotFoundError(f"mesh {mesh.name!r} of link(s) {links}: file {mesh.file!r} does not exist")
            try:
                set_user_mesh(mesh, load_mesh(mesh.file))
            except Exception as err:
                raise ValueError(
                    f"cannot read mesh file {mesh.file!r} (mesh {mesh.name!r}, used by link(s) {links}): {err}"
                ) from err


def list_joints(spec: mujoco.MjSpec) -> list[JointInfo]:
    """Joints of a spec in its order, each with its range (None when unlimited).

    A joint whose ``limited`` is ``auto`` counts as limited when its range is not empty (MuJoCo's
    default ``autolimits``).
    """
    out = []
    for joint in spec.joints:
        lo, hi = (float(x) for x in joint.range)
        out.append(
            JointInfo(
                joint.name,
                _JOINT_TYPES.get(joint.type, str(joint.type)),
                (lo, hi) if _is_limited(joint.limited, lo, hi) else None,
            )
        )
    return out


def joint_dynamics(spec: mujoco.MjSpec) -> dict[str, dict[str, Any]]:
    """Per joint: ``damping``, ``frictionloss``, ``armature`` and ``actfrcrange`` (or None)."""
    out = {}
    for joint in spec.joints:
        damping = joint.damping
        lo, hi = (float(x) for x in joint.actfrcrange)
        out[joint.name] = {
            "damping": float(damping[0]) if hasattr(damping, "__len__") else float(damping),
            "frictionloss": float(joint.frictionloss),
            "armature": float(joint.armature),
            "actfrcrange": (lo, hi) if _is_limited(joint.actfrclimited, lo, hi) else None,
        }
    return out


def _is_limited(flag: Any, lo: float, hi: float) -> bool:
    """MuJoCo's limited flag, with ``auto`` meaning "the range is not empty"."""
    return flag == mujoco.mjtLimited.mjLIMITED_TRUE or (flag == mujoco.mjtLimited.mjLIMITED_AUTO and lo < hi)
