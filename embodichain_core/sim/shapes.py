"""Shape configs of rigid objects: primitives and meshes."""

from __future__ import annotations

from typing import List, Optional

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.configclass import MISSING, configclass
from embodichain_core.utils.suggest import did_you_mean


@configclass
class VisualMaterialCfg:
    """Render material of a shape.

    ``base_color`` is RGBA in [0, 1]; ``base_color_texture`` is an image path
    (resolved with ``get_data_path``) mapped with the mesh's texture coordinates.
    """

    uid: str = "default_mat"
    base_color: tuple = (0.5, 0.5, 0.5, 1.0)
    metallic: float = 0.0
    roughness: float = 0.7
    emissive: tuple = (0.0, 0.0, 0.0)
    emissive_intensity: float = 0.0
    base_color_texture: Optional[str] = None
    metallic_texture: Optional[str] = None
    roughness_texture: Optional[str] = None
    normal_texture: Optional[str] = None
    ao_texture: Optional[str] = None
    ior: float = 1.5
    material_type: str = "BRDF"


@configclass
class LoadOption:
    """Mesh loading options (kept for EmbodiChain config compatibility)."""

    rebuild_normals: bool = False
    rebuild_tangent: bool = False
    rebuild_3rdnormal: bool = False
    rebuild_3rdtangent: bool = False
    smooth: float = -1.0


@configclass
class ShapeCfg:
    """Base of all shapes; ``shape_type`` selects the subclass in ``from_dict``."""

    shape_type: str = ""
    visual_material: Optional[VisualMaterialCfg] = None

    @classmethod
    def _resolve_subclass(cls, data: dict, path: str) -> type:
        if cls is not ShapeCfg:
            return cls
        kinds = {c.__name__[:-3].lower(): c for c in (MeshCfg, CubeCfg, SphereCfg, CylinderCfg, CapsuleCfg)}
        kind = str(data.get("shape_type", "")).lower()
        if kind not in kinds:
            names = [c.__name__[:-3] for c in kinds.values()]
            reason = f"unknown shape_type {data.get('shape_type')!r}.{did_you_mean(kind, names)}"
            raise ConfigError(f"{path}.shape_type" if path else "shape_type", reason)
        return kinds[kind]


@configclass
class MeshCfg(ShapeCfg):
    """A triangle mesh (``.ply``, ``.obj``, ``.stl``, ``.glb``).

    Collision uses the mesh's convex components; a non-convex component is
    decomposed with coacd into at most ``max_convex_hull_num`` hulls (cached).
    """

    shape_type: str = "Mesh"
    fpath: str = MISSING
    load_option: LoadOption = LoadOption()
    compute_uv: bool = False
    project_direction: List[float] = [1.0, 1.0, 1.0]
    max_convex_hull_num: int = 1
    acd_method: str = "coacd"
    sdf_resolution: int = 0


@configclass
class CubeCfg(ShapeCfg):
    """A box; ``size`` is the full extent along x, y, z in metres."""

    shape_type: str = "Cube"
    size: List[float] = [1.0, 1.0, 1.0]


@configclass
class SphereCfg(ShapeCfg):
    """A sphere of ``radius`` metres."""

    shape_type: str = "Sphere"
    radius: float = 1.0
    resolution: int = 20


@configclass
class CylinderCfg(ShapeCfg):
    """A cylinder along z, ``height`` is the full length."""

    shape_type: str = "Cylinder"
    radius: float = 0.05
    height: float = 0.1


@configclass
class CapsuleCfg(ShapeCfg):
    """A capsule along z, ``height`` is the length of the cylindrical part."""

    shape_type: str = "Capsule"
    radius: float = 0.05
    height: float = 0.1
