"""The scene: builds entities into one model, owns the batch and the entities.

Example:
    >>> scene = Scene(SimulationManagerCfg(), num_envs=4)
    >>> scene.add_rigid_object(RigidObjectCfg(uid="cube", init_pos=(0, 0, 0.1)))
    >>> scene.build()
    >>> scene["cube"].get_local_pose().shape
    torch.Size([4, 7])
"""

from __future__ import annotations

from typing import Any, Optional

import mujoco
import torch

from embodichain_core.sim.backend import BatchSim, SimBackend
from embodichain_core.sim.scene_build.builder import GROUND_UID, SceneBuilder
from embodichain_core.sim.scene_build.builder_articulation import add_articulation
from embodichain_core.sim.scene_build.builder_objects import add_rigid_object, add_rigid_object_group
from embodichain_core.sim.cfg import (
    ArticulationCfg,
    LightCfg,
    RigidObjectCfg,
    RigidObjectGroupCfg,
    SimulationManagerCfg,
)
from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.base import Entity, StateSlices, env_index
from embodichain_core.sim.entities.group import RigidObjectGroup
from embodichain_core.sim.entities.light import Light
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.entities.robot import Robot
from embodichain_core.sim.scene_defaults import DefaultRows
from embodichain_core.utils.suggest import did_you_mean

#: State fields a kept entity's columns are read from, with the ``StateSlices`` field indexing them.
_COLUMN_FIELDS = (("qpos", "qpos"), ("qvel", "qvel"), ("ctrl", "ctrl"), ("mocap_pos", "mocap"), ("mocap_quat", "mocap"))


class Scene:
    """Entities of one env definition, simulated ``num_envs`` times."""

    def __init__(self, sim_cfg: SimulationManagerCfg, num_envs: int, device: str = "cpu"):
        self.sim_cfg = sim_cfg
        self.num_envs = int(num_envs)
        self.device = torch.device(device)
        self.builder = SceneBuilder(sim_cfg)  # kept after build: the records name what it added
        self._model: Optional[mujoco.MjModel] = None  # set by build(), see the properties below
        self._sim: Optional[SimBackend] = None
        self.entities: dict[str, Entity] = {}
        self.robots: dict[str, Robot] = {}
        self.articulations: dict[str, Articulation] = {}
        self.rigid_objects: dict[str, RigidObject] = {}
        self.backgrounds: dict[str, RigidObject] = {}
        self.groups: dict[str, RigidObjectGroup] = {}
        self.lights: dict[str, Light] = {}
        self.sensors: dict[str, Any] = {}
        self.current_mesh: dict[str, list] = {}
        self.defaults = DefaultRows(self)  # the saved default state row of resets

    # -- adding (before build) -------------------------------------------------------------
    def add_robot(self, cfg: ArticulationCfg, path: str = "robot") -> None:
        add_articulation(self._b(), cfg, "robot", path)

    def add_articulation(self, cfg: ArticulationCfg, path: str = "articulation") -> None:
        add_articulation(self._b(), cfg, "articulation", path)

    def add_rigid_object(self, cfg: RigidObjectCfg, path: str = "rigid_object", background: bool = False) -> None:
        add_rigid_object(self._b(), cfg, "background" if background else "rigid_object", path)

    def add_rigid_object_group(self, cfg: RigidObjectGroupCfg, path: str = "rigid_object_group") -> None:
        add_rigid_object_group(self._b(), cfg, path)

    def add_light(self, cfg: LightCfg, path: str = "light.direct") -> None:
        self._b().add_light(cfg, path)

    def add_sensor(self, sensor: Any, path: str = "sensor") -> None:
        """Add a constructed sensor (a :class:`BaseSensor`); it edits the spec now."""
        self._b().claim_uid(sensor.uid, "sensor", sensor.cfg, path)
        sensor.build(self._b())
        self.sensors[sensor.uid] = sensor

    def reserve_mesh_variants(self, uid: str, files: list[str]) -> None:
        """Before build: let mesh object ``uid`` take any mesh of ``files`` per env."""
        from embodichain_core.sim.scene_build.variants import add_variants

        record = self._b().record(uid)
        if record.kind not in ("rigid_object", "background") or "mesh_file" not in record.extra:
            raise ValueError(f"{uid!r} is not a mesh rigid object; only those can swap meshes per env")
        add_variants(self._b(), uid, [str(f) for f in files])

    def reserve_scale_variants(self, uid: str, factors: list) -> list[str]:
        """Before build: let mesh object ``uid`` take its mesh scaled by any of ``factors``
        ((sx, sy, sz) each) per env; returns the variant keys for :meth:`set_mesh_variants`."""
        from embodichain_core.sim.scene_build.variants import add_variants

        record = self._b().record(uid)
        if record.kind not in ("rigid_object", "background") or "mesh_file" not in record.extra:
            raise ValueError(f"{uid!r} is not a mesh rigid object; only those have scale variants")
        return add_variants(self._b(), uid, [], factors=[tuple(f) for f in factors])

    def set_mesh_variant(self, uid: str, fpath: str, env_ids: Any = None) -> None:
        """After build: ``env_ids`` simulate and render ``uid`` with the mesh ``fpath``
        (reserved before build). The object's body keeps its pose."""
        ids = env_index(env_ids, self.num_envs)
        self.set_mesh_variants(uid, [str(fpath)] * len(ids), ids)

    def set_mesh_variants(self, uid: str, keys: list[str], env_ids: Any = None) -> None:
        """After build: env ``env_ids[i]`` uses variant ``keys[i]`` (a reserved file or scale key)."""
        from embodichain_core.sim.scene_build.variants import apply_variants

        ids = env_index(env_ids, self.num_envs)
        if len(keys) != len(ids):
            raise ValueError(f"{uid}: {len(keys)} variant keys for {len(ids)} envs")
        apply_variants(self, uid, [str(k) for k in keys], ids)
        current = self.current_mesh.setdefault(uid, [self.builder.record(uid).extra.get("mesh_file")] * self.num_envs)
        for env, key in zip(ids.tolist(), keys):
            current[env] = str(key)

    def _b(self) -> SceneBuilder:
        if self._model is not None:
            raise RuntimeError("the scene is already built; add entities before build()")
        return self.builder

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled model (after :meth:`build`)."""
        if self._model is None:
            raise RuntimeError("the scene is not built yet; call build() first")
        return self._model

    @property
    def sim(self) -> SimBackend:
        """The simulation backend stepping the ``num_envs`` copies (after :meth:`build`)."""
        if self._sim is None:
            raise RuntimeError("the scene is not built yet; call build() first")
        return self._sim

    # -- build -------------------------------------------------------------------------------
    def build(self) -> None:
        """Compile the model, create the batch and the entities, reset every env."""
        self._model = self._b().compile()
        cfg = self.sim_cfg
        sim: SimBackend
        if cfg.backend == "warp":  # MuJoCo Warp (docs/backends.md)
            from embodichain_core.sim.backend.warp_sim import WarpSim

            sim = WarpSim(self.model, self.num_envs, substeps=cfg.physics_substeps, device=cfg.sim_device)
        else:
            sim = BatchSim(
                self.model,
                self.num_envs,
                substeps=cfg.physics_substeps,
                nthread=int(cfg.cpu_num or 0),
                persistent=cfg.persistent,
            )
        self._sim = sim
        if any(rec.extra.get("variants") for rec in self.builder.records.values()):
            from embodichain_core.sim.scene_build.variants import variant_fields

            # per-env meshes switch collision filters (warp: park the unused geoms out of reach)
            sim.declare_per_env(variant_fields(self.builder))
        for uid, rec in self.builder.records.items():
            self._make_entity(uid, rec)
        for sensor in self.sensors.values():
            sensor.bind()
        self.reset()

    def _make_entity(self, uid: str, rec: Any) -> None:
        kinds: dict[str, tuple[type[Articulation], dict[str, Any]]] = {
            "robot": (Robot, self.robots),
            "articulation": (Articulation, self.articulations),
        }
        if rec.kind in kinds:
            cls, store = kinds[rec.kind]
            store[uid] = self.entities[uid] = cls(uid, rec.cfg, self, rec)
        elif rec.kind in ("rigid_object", "background"):
            obj = RigidObject(uid, rec.cfg, self, parts=rec.extra)
            (self.rigid_objects if rec.kind == "rigid_object" else self.backgrounds)[uid] = obj
            self.entities[uid] = obj
        elif rec.kind == "group":
            self.groups[uid] = self.entities[uid] = RigidObjectGroup(uid, rec.cfg, self, rec, rec.extra["parts"])
        elif rec.kind == "light":
            self.lights[uid] = self.entities[uid] = Light(uid, rec.cfg, self)
        elif rec.kind == "sensor":
            self.entities[uid] = self.sensors[uid]

    # -- access ------------------------------------------------------------------------------------
    @property
    def asset_uids(self) -> list[str]:
        """Every uid a ``SceneEntityCfg`` may name."""
        return [GROUND_UID] + list(self.entities)

    def __getitem__(self, uid: str) -> Any:
        if uid not in self.entities:
            raise KeyError(f"no entity with uid {uid!r} in the scene.{did_you_mean(uid, self.asset_uids)}")
        return self.entities[uid]

    def __contains__(self, uid: str) -> bool:
        return uid in self.entities

    def get(self, uid: str, default: Any = None) -> Any:
        return self.entities.get(uid, default)

    def state_slices(self, uids: Any) -> StateSlices:
        """The state columns owned by the entities ``uids`` (each declares its own)."""
        return sum((self[uid].state_slices() for uid in uids), StateSlices())

    def reset(self, env_ids: Any = None, keep_uids: Any = ()) -> None:
        """Reset envs ``env_ids`` (all when None): their whole state rows (clears anything
        a diverged simulation left behind), then every entity's initial state, except
        the entities ``keep_uids``, whose state columns keep their values.

        Once a reset has run, the rows come from the saved default row (model defaults
        and every entity's initial state, see :mod:`embodichain_core.sim.scene_defaults`)
        in one write, and the entities whose reset only writes state
        (``Entity.state_only_reset``) are not run again.
        """
        ids = env_index(env_ids, self.num_envs)
        keep = set(keep_uids)
        kept = self._read_columns(ids, self.state_slices(keep_uids)) if keep else {}
        row = self.defaults.row()
        self.sim.reset(ids, state=row)
        for uid, ent in self.entities.items():
            if uid not in keep and not (row is not None and ent.state_only_reset):
                ent.reset(ids)
        if row is None and not keep:  # rows at model defaults + every entity's initial state: save one
            self.defaults.capture(ids)
        if kept:
            self._write_columns(ids, kept)

    def _read_columns(self, ids: torch.Tensor, cols: StateSlices) -> dict[str, tuple[list[int], torch.Tensor]]:
        """Copies of the ``cols`` of rows ``ids``, by state field."""
        out = {}
        for name, key in _COLUMN_FIELDS:
            idx = getattr(cols, key)
            if idx:
                out[name] = (idx, getattr(self.sim, name)[ids][:, idx].clone())
        return out

    def _write_columns(self, ids: torch.Tensor, saved: dict[str, tuple[list[int], torch.Tensor]]) -> None:
        for name, (idx, values) in saved.items():
            getattr(self.sim, name)[ids[:, None], torch.as_tensor(idx)[None, :]] = values
        self.sim.mark_dirty(ids)

    # -- per-env options ---------------------------------------------------------------------------
    def set_gravity(self, gravity: Any, env_ids: Any = None) -> None:
        """Gravity (m/s^2) per env: ``(3,)`` for every env of ``env_ids``, or ``(n, 3)``.

        Raises:
            ValueError: a bad shape, or a backend where gravity is one global option.
        """
        from embodichain_core.sim.entities.model_fields import set_gravity

        set_gravity(self.sim, gravity, env_ids)

    def get_gravity(self, env_ids: Any = None) -> torch.Tensor:
        """(n, 3) gravity of ``env_ids`` (all envs when None)."""
        from embodichain_core.sim.entities.model_fields import get_gravity

        return get_gravity(self.sim, env_ids)
