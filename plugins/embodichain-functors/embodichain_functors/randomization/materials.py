"""Visual materials: a deterministic material for rigid objects, and per-env random base
colours and textures for objects, groups, articulations and the ground.

Textures must be in the model before it is compiled, so the class functors add
them in ``modify_scene`` (each file once, shared by every functor); per env they
then pick a texture by writing the material's ``mat_texid`` and colour
``mat_rgba`` model fields. MuJoCo loads PNG textures.
"""

from __future__ import annotations

import hashlib
import os
from typing import Any, Optional

import mujoco
import numpy as np

from embodichain_core.managers import DataPath
from embodichain_core.sim.scene_build.builder import GROUND_UID
from embodichain_core.sim.data import get_data_path
from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.shapes import VisualMaterialCfg

from embodichain_functors._common import (
    ParamError,
    as_range,
    check_optional_range,
    check_positive,
    check_probability,
    env_ids_of,
    randint,
    uniform_np,
)
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._sim import write_model

VISUAL = "randomization.visual"
RGB_ROLE = int(mujoco.mjtTextureRole.mjTEXROLE_RGB)
USE_MATERIAL_RGBA = [0.5, 0.5, 0.5, 1.0]  # a geom with MuJoCo's default rgba shows its material's colour

__all__ = ["randomize_visual_material", "set_rigid_object_visual_material", "set_rigid_object_group_visual_material"]


def uid_of(entity_cfg: Any) -> str:
    """The uid of a ``SceneEntityCfg`` or of its dict form (configs before resolution)."""
    return entity_cfg["uid"] if isinstance(entity_cfg, dict) else entity_cfg.uid


def texture_name(path: str) -> str:
    """The spec name of a texture file (one texture per file, whoever adds it)."""
    return "embodichain_functors/tex/" + hashlib.sha1(os.path.abspath(path).encode()).hexdigest()[:16]


def add_texture(spec: mujoco.MjSpec, path: str) -> str:
    """Add ``path`` as a 2D texture unless it is there already; return its name."""
    name = texture_name(path)
    if spec.texture(name) is None:
        tex = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D)
        tex.file = path
    return name


def texture_files(texture_path: str, max_textures: int, functor: str) -> list[str]:
    """PNG files of a folder (an asset name or a path), at most ``max_textures`` evenly spread."""
    try:
        folder = get_data_path(texture_path)
    except FileNotFoundError as err:
        raise ParamError(functor, "texture_path", str(err).splitlines()[0]) from None
    if not os.path.isdir(folder):
        raise ParamError(functor, "texture_path", f"{folder!r} is not a folder")
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith(".png"))
    if len(files) > max_textures:
        files = [files[int(i * len(files) / max_textures)] for i in range(max_textures)]
    return [os.path.join(folder, f) for f in files]


def own_link_materials(spec: mujoco.MjSpec, uid: str, links: list[str]) -> None:
    """Give every visible geom of an articulation's links its own material (same look)."""
    for link in links:
        for k, geom in enumerate(spec.body(f"{uid}/{link}").geoms):
            name = f"embodichain_functors/mat/{uid}/{link}/{k}"
            if spec.material(name) is not None or float(geom.rgba[3]) == 0.0:
                continue
            old = spec.material(geom.material) if geom.material else None
            explicit = [float(v) for v in geom.rgba] != USE_MATERIAL_RGBA
            mat = spec.add_material(name=name)
            mat.rgba = list(geom.rgba) if explicit or old is None else list(old.rgba)
            if old is not None:
                for role, tex in enumerate(old.textures):
                    mat.textures[role] = tex
                mat.texrepeat, mat.texuniform = old.texrepeat, old.texuniform
            geom.material, geom.rgba = name, USE_MATERIAL_RGBA


def material_groups(scene: Any, uid: str, functor: str) -> list[list[int]]:
    """Material ids of an entity, grouped by part drawn independently (member, link)."""
    model = scene.model

    def find(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, name)

    if uid == GROUND_UID:
        return [[find(f"{GROUND_UID}/mat")]]
    entity = scene.get(uid)
    if isinstance(entity, RigidObject):
        return [[entity.material_id]]
    if isinstance(entity, RigidObjectGroup):
        return [[m.material_id] for m in entity.members]
    if isinstance(entity, Articulation):
        prefix = f"embodichain_functors/mat/{uid}/"
        groups: dict[str, list[int]] = {}
        for m in range(model.nmat):
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_MATERIAL, m) or ""
            if name.startswith(prefix):
                groups.setdefault(name[len(prefix) :].rsplit("/", 1)[0], []).append(m)
        return list(groups.values())
    raise ParamError(functor, "entity_cfg", f"{uid!r} is not a rigid object, group, articulation or {GROUND_UID!r}")


class randomize_visual_material(CheckedFunctor):
    """Per env and per part, a random texture (with a probability) or a random base colour.

    Parts are the object, each member of a group, or each link of an articulation;
    ``"default_plane"`` randomizes the ground. A part drawing a texture shows it
    untinted; otherwise it gets a colour from ``base_color_range`` (without a
    colour range it keeps its original look).

    Args (params):
        entity_cfg: the rigid object, background, group, articulation, or ``default_plane``.
        random_texture_prob: probability of a texture (needs ``texture_path``).
        texture_path: folder (asset name or path) of PNG textures.
        base_color_range: ``[[r, g, b] low, [r, g, b] high]`` in [0, 1].
        metallic_range: ``[low, high]`` of the material's metallic value.
        roughness_range: ``[low, high]`` of the material's roughness.
        max_textures: at most this many textures of the folder are loaded (evenly spread).

    Example:
        ``{"func": "randomize_visual_material", "mode": "interval", "interval_step": 10, "params":
        {"entity_cfg": {"uid": "table"}, "random_texture_prob": 0.5, "texture_path": "textures/wood",
        "base_color_range": [[0.2, 0.2, 0.2], [1.0, 1.0, 1.0]]}}``
    """

    embodichain_category = VISUAL

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Add the folder's textures and, for articulations, one material per link geom."""
        params = cfg.params
        uid = uid_of(params["entity_cfg"])
        if params.get("texture_path"):
            for path in texture_files(params["texture_path"], int(params.get("max_textures", 64)), cls.__name__):
                add_texture(scene.builder.spec, path)
        record = scene.builder.records.get(uid)
        if record is not None and record.kind in ("robot", "articulation"):
            own_link_materials(scene.builder.spec, uid, record.extra["bodies"])

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        params, model = cfg.params, env.scene.model
        self.groups = material_groups(env.scene, uid_of(params["entity_cfg"]), type(self).__name__)
        files = (
            texture_files(params["texture_path"], int(params.get("max_textures", 64)), type(self).__name__)
            if params.get("texture_path")
            else []
        )
        self.textures = np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, texture_name(f)) for f in files], dtype=np.int64
        )
        mats = [m for group in self.groups for m in group]
        self._mats = np.asarray(mats, dtype=np.int64)
        self._part = np.array([g for g, group in enumerate(self.groups) for _ in group], dtype=np.int64)
        self._rgba0 = np.array(model.mat_rgba[mats], dtype=np.float64)
        self._tex0 = np.array(model.mat_texid[mats, RGB_ROLE], dtype=np.int64)

    def check(
        self,
        env: Any,
        entity_cfg: Any = None,
        random_texture_prob: Any = 0.5,
        texture_path: Any = None,
        base_color_range: Any = None,
        metallic_range: Any = None,
        roughness_range: Any = None,
        max_textures: Any = 64,
    ) -> None:
        name = type(self).__name__
        if not material_groups(env.scene, uid_of(entity_cfg), name):
            raise ParamError(name, "entity_cfg", f"{uid_of(entity_cfg)!r} has no visible geom to recolour")
        check_probability(random_texture_prob, name, "random_texture_prob")
        check_positive(max_textures, name, "max_textures")
        check_optional_range(base_color_range, name, "base_color_range", 3)
        check_optional_range(metallic_range, name, "metallic_range")
        check_optional_range(roughness_range, name, "roughness_range")
        if texture_path and not texture_files(texture_path, int(max_textures), name):
            raise ParamError(name, "texture_path", f"no PNG textures in {texture_path!r}")

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        entity_cfg: Any,
        random_texture_prob: float = 0.5,
        texture_path: Optional[DataPath] = None,
        base_color_range: Any = None,
        metallic_range: Any = None,
        roughness_range: Any = None,
        max_textures: int = 64,
    ) -> None:
        ids = env_ids_of(env, env_ids)
        n, parts = len(ids), len(self.groups)
        rgba = np.repeat(self._rgba0[None], n, axis=0)
        texid = np.repeat(self._tex0[None], n, axis=0)
        if base_color_range is not None:
            low, high = as_range(base_color_range, type(self).__name__, "base_color_range", 3)
            color = uniform_np(env, ids, low, high, (parts,))
            rgba[..., :3], texid[:] = color[:, self._part], -1
        if len(self.textures) and random_texture_prob > 0:
            use = (env.rng.random(ids, (parts,)) < random_texture_prob)[:, self._part]
            pick = self.textures[randint(env, ids, len(self.textures), (parts,)).numpy()][:, self._part]
            texid = np.where(use, pick, texid)
            rgba = np.where(use[..., None], 1.0, rgba)
        writes = [("mat_rgba", self._mats, rgba), ("mat_texid", (self._mats, RGB_ROLE), texid)]
        for field, param, rng in (
            ("mat_metallic", "metallic_range", metallic_range),
            ("mat_roughness", "roughness_range", roughness_range),
        ):
            if rng is not None:
                low, high = as_range(rng, type(self).__name__, param)
                writes.append((field, self._mats, uniform_np(env, ids, low, high, (parts,))[:, self._part]))
        write_model(env.sim, ids, writes)


def material_cfg(mat_cfg: Any, functor: str) -> VisualMaterialCfg:
    """A :class:`VisualMaterialCfg` from a config object or its dict form."""
    if isinstance(mat_cfg, VisualMaterialCfg):
        return mat_cfg
    if isinstance(mat_cfg, dict):
        try:
            return VisualMaterialCfg.from_dict(mat_cfg)
        except ValueError as err:
            raise ParamError(functor, "mat_cfg", str(err)) from None
    raise ParamError(functor, "mat_cfg", f"expected a VisualMaterialCfg or a dict, got {type(mat_cfg).__name__}")


class set_rigid_object_visual_material(CheckedFunctor):
    """Give a rigid object (or every member of a group) a fixed material in ``env_ids``.

    Sets the base colour, metallic, roughness, emission and, with
    ``base_color_texture``, a texture (a PNG, added to the model before compile).
    Not a randomization: ``filter_visual_rand`` keeps it.

    Args (params):
        entity_cfg: the rigid object or background (a group with the ``_group_`` variant).
        mat_cfg: a ``VisualMaterialCfg`` or its dict (``base_color`` RGB or RGBA in [0, 1]).

    Example:
        ``{"func": "set_rigid_object_visual_material", "mode": "startup", "params": {"entity_cfg":
        {"uid": "cube"}, "mat_cfg": {"base_color": [0.8, 0.1, 0.1, 1.0], "roughness": 0.4}}}``
    """

    kinds: tuple = (RigidObject,)

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Add the material's texture (if any) to the spec."""
        mat = material_cfg(cfg.params.get("mat_cfg"), cls.__name__)
        if mat.base_color_texture:
            add_texture(scene.builder.spec, get_data_path(mat.base_color_texture))

    def check(self, env: Any, entity_cfg: Any = None, mat_cfg: Any = None) -> None:
        name = type(self).__name__
        if not isinstance(env.scene.get(uid_of(entity_cfg)), self.kinds):
            kinds = " or ".join(k.__name__ for k in self.kinds)
            raise ParamError(name, "entity_cfg", f"{uid_of(entity_cfg)!r} is not a {kinds}")
        color = material_cfg(mat_cfg, name).base_color
        if len(color) not in (3, 4) or any(not 0.0 <= float(c) <= 1.0 for c in color):
            raise ParamError(name, "mat_cfg", f"base_color must be 3 or 4 values in [0, 1], got {color!r}")

    def __call__(self, env: Any, env_ids: Any, entity_cfg: Any, mat_cfg: Any) -> None:
        ids = env_ids_of(env, env_ids)
        mat = material_cfg(mat_cfg, type(self).__name__)
        mats = [m for group in material_groups(env.scene, uid_of(entity_cfg), type(self).__name__) for m in group]
        texid = -1
        if mat.base_color_texture:
            name = texture_name(get_data_path(mat.base_color_texture))
            texid = mujoco.mj_name2id(env.scene.model, mujoco.mjtObj.mjOBJ_TEXTURE, name)
        rgba = list(mat.base_color) + [1.0] * (4 - len(mat.base_color))
        emission = float(mat.emissive_intensity) * max(float(c) for c in mat.emissive)
        writes = [
            ("mat_rgba", mats, np.array(rgba)),
            ("mat_texid", (mats, RGB_ROLE), texid),
            ("mat_metallic", mats, float(mat.metallic)),
            ("mat_roughness", mats, float(mat.roughness)),
            ("mat_emission", mats, emission),
        ]
        write_model(env.sim, ids, writes)


class set_rigid_object_group_visual_material(set_rigid_object_visual_material):
    """Give every member of a rigid-object group a fixed material in ``env_ids``.

    Args (params):
        entity_cfg: the group.
        mat_cfg: a ``VisualMaterialCfg`` or its dict.

    Example:
        ``{"func": "set_rigid_object_group_visual_material", "mode": "startup", "params":
        {"entity_cfg": {"uid": "blocks"}, "mat_cfg": {"base_color": [0.1, 0.6, 0.1]}}}``
    """

    kinds = (RigidObjectGroup,)
