"""Scene building on ``mujoco.MjSpec``: world, options, ground, lights.

Entities are added by :mod:`builder_objects` and :mod:`builder_articulation`;
every element an entity owns is named ``"<uid>/<name>"`` so names stay unique.

Example:
    >>> b = SceneBuilder(SimulationManagerCfg())
    >>> b.add_light(LightCfg(uid="point", init_pos=(0, 0, 2)))
    >>> model = b.compile()
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import math

import mujoco
import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import LightCfg, SimulationManagerCfg
from embodichain_core.utils.suggest import did_you_mean

GROUND_UID = "default_plane"
VISUAL_GROUP = 2
COLLISION_GROUP = 3

_INTEGRATORS = {
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "Euler": mujoco.mjtIntegrator.mjINT_EULER,
    "RK4": mujoco.mjtIntegrator.mjINT_RK4,
}
_SOLVERS = {"Newton": mujoco.mjtSolver.mjSOL_NEWTON, "CG": mujoco.mjtSolver.mjSOL_CG, "PGS": mujoco.mjtSolver.mjSOL_PGS}


@dataclass
class EntityRecord:
    """What the builder added for one entity (names are looked up after compile)."""

    uid: str
    kind: str  # robot | articulation | rigid_object | background | light | group | sensor
    cfg: Any
    root_body: str | None = None
    extra: dict = field(default_factory=dict)
    path: str = ""  # where its config sits (``robot``, ``articulation[1]``), for error messages


class SceneBuilder:
    """Accumulates a scene into one ``MjSpec`` and compiles it."""

    def __init__(self, sim_cfg: SimulationManagerCfg):
        self.sim_cfg = sim_cfg
        self.spec = mujoco.MjSpec()
        self.spec.modelname = "embodichain_scene"
        self.records: dict[str, EntityRecord] = {}
        self._post_compile: list[Callable[[mujoco.MjModel], None]] = []
        self.collision_bit = 0  # the last articulation's collision bit (builder_articulation)
        self._sleep_speed: float | None = None  # the sleep tolerance from sleep_threshold (sleep_policy)
        self._configure_options()
        self.add_ground()

    # -- world -------------------------------------------------------------------------
    def _configure_options(self) -> None:
        cfg, phys = self.sim_cfg, self.sim_cfg.physics_config
        if not np.isfinite(cfg.physics_dt) or cfg.physics_dt <= 0:
            raise ConfigError("sim_cfg.physics_dt", f"must be a finite number > 0, got {cfg.physics_dt!r}")
        if isinstance(cfg.physics_substeps, bool) or int(cfg.physics_substeps) < 1:
            raise ConfigError("sim_cfg.physics_substeps", f"must be an int >= 1, got {cfg.physics_substeps!r}")
        opt = self.spec.option
        opt.timestep = cfg.physics_dt / int(cfg.physics_substeps)
        opt.gravity = np.asarray(phys.gravity, dtype=float)
        opt.integrator = _INTEGRATORS[phys.integrator]
        opt.solver = _SOLVERS[phys.solver]
        opt.iterations = int(phys.iterations)
        # a diverging simulation must surface (non-finite state) so the env can
        # warn and reset that env, instead of MuJoCo silently resetting it
        opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        if phys.enable_sleep:
            opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC if phys.cone == "elliptic" else mujoco.mjtCone.mjCONE_PYRAMIDAL
        self.spec.compiler.autolimits = True
        self.spec.visual.global_.offwidth = max(int(cfg.width), 640)
        self.spec.visual.global_.offheight = max(int(cfg.height), 480)
        self.spec.visual.headlight.diffuse = [0.35, 0.35, 0.35]
        self.spec.visual.headlight.ambient = [0.25, 0.25, 0.25]

    def add_ground(self) -> None:
        """The ground plane, uid ``default_plane``, with a checker material."""
        tex = self.spec.add_texture(name=f"{GROUND_UID}/tex", type=mujoco.mjtTexture.mjTEXTURE_2D)
        tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_CHECKER
        tex.rgb1, tex.rgb2 = [0.42, 0.44, 0.47], [0.36, 0.38, 0.41]
        tex.width = tex.height = 256
        mat = self.spec.add_material(name=f"{GROUND_UID}/mat")
        mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = f"{GROUND_UID}/tex"
        mat.texrepeat = [8, 8]
        mat.reflectance = 0.0
        self.spec.worldbody.add_geom(
            name=GROUND_UID,
            type=mujoco.mjtGeom.mjGEOM_PLANE,
            size=[0, 0, 0.05],
            material=f"{GROUND_UID}/mat",
            contype=1,
            conaffinity=(1 << 30) - 1,
        )
        self.records[GROUND_UID] = EntityRecord(GROUND_UID, "ground", None)

    # -- bookkeeping -----------------------------------------------------------------------
    def claim_uid(self, uid: Any, kind: str, cfg: Any, path: str) -> EntityRecord:
        """Register a new entity uid; duplicates and empty uids are config errors."""
        if not uid or not isinstance(uid, str):
            raise ConfigError(f"{path}.uid", f"every {kind} needs a string uid, got {uid!r}")
        if "/" in uid:
            raise ConfigError(f"{path}.uid", f"uid {uid!r} must not contain '/'")
        if uid in self.records:
            other = self.records[uid].kind
            raise ConfigError(f"{path}.uid", f"uid {uid!r} is already used by a {other}; uids must be unique")
        record = EntityRecord(uid, kind, cfg, path=path)
        self.records[uid] = record
        return record

    def require_iterations(self, *owners: Any) -> None:
        """Raise MuJoCo's solver ``iterations`` (one setting for the whole model) to at least
        ``min_position_iters + min_velocity_iters`` of each owner (PhysX's per-body solver
        iteration counts; a config or its ``attrs``)."""
        for owner in owners:
            need = int(owner.min_position_iters) + int(owner.min_velocity_iters)
            self.spec.option.iterations = max(int(self.spec.option.iterations), need)

    def sleep_policy(self, body: Any, threshold: float) -> None:
        """Map a body's ``sleep_threshold`` (PhysX: kinetic energy per unit mass) onto MuJoCo's
        sleeping, when ``physics_config.enable_sleep`` is on: 0 keeps the body's tree awake;
        otherwise the model's velocity tolerance becomes at most ``sqrt(2 * threshold)`` (the
        speed of that kinetic energy), the smallest of all bodies (MuJoCo has one tolerance)."""
        if not self.sim_cfg.physics_config.enable_sleep:
            return
        if float(threshold) <= 0:
            body.sleep = mujoco.mjtSleepPolicy.mjSLEEP_NEVER
            return
        speed = math.sqrt(2.0 * float(threshold))
        self._sleep_speed = speed if self._sleep_speed is None else min(self._sleep_speed, speed)
        self.spec.option.sleep_tolerance = self._sleep_speed

    def on_compile(self, fn: Callable[[mujoco.MjModel], None]) -> None:
        """Run ``fn(model)`` on every compiled model (base and variants)."""
        self._post_compile.append(fn)

    def record(self, uid: str) -> EntityRecord:
        if uid not in self.records:
            raise KeyError(f"no entity {uid!r} in the scene.{did_you_mean(uid, self.records)}")
        return self.records[uid]

    # -- lights ----------------------------------------------------------------------------
    def add_light(self, cfg: LightCfg, path: str = "light.direct") -> EntityRecord:
        """Add a light as a world light named after its uid."""
        from embodichain_core.utils.math import init_pos_from_cfg

        record = self.claim_uid(cfg.uid, "light", cfg, path)
        kind = cfg.light_type
        light = self.spec.worldbody.add_light(name=cfg.uid)
        light.pos = init_pos_from_cfg(cfg.init_pos, cfg.init_local_pose)
        direction = np.asarray(cfg.direction, dtype=float)
        light.dir = direction / max(np.linalg.norm(direction), 1e-9)
        light.castshadow = bool(cfg.enable_shadow)
        if kind in ("sun", "direction", "directional"):
            light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        elif kind == "spot":
            light.type = mujoco.mjtLightType.mjLIGHT_SPOT
            light.cutoff = float(cfg.spot_angle_outer)
            light.exponent = max(1.0, float(cfg.spot_angle_outer - cfg.spot_angle_inner))
        else:
            # MuJoCo's OpenGL renderer draws no mjLIGHT_POINT: an all-round spot
            # without falloff lights the same way and renders everywhere
            light.type = mujoco.mjtLightType.mjLIGHT_SPOT
            light.cutoff, light.exponent = 180.0, 0.0
            light.attenuation = [1.0, 0.0, 0.0]
            light.range = float(cfg.radius)
        light.diffuse = light_diffuse(cfg.color, cfg.intensity)
        light.specular = [0.2, 0.2, 0.2]
        light.intensity = float(cfg.intensity)
        return record

    def compile(self) -> mujoco.MjModel:
        """Compile the spec; errors name the scene element MuJoCo complained about."""
        return self.compile_spec(self.spec)

    def compile_spec(self, spec: mujoco.MjSpec) -> mujoco.MjModel:
        try:
            model = spec.compile()
        except Exception as err:  # mujoco raises ValueError with the XML element
            from embodichain_core.sim.scene_build.import_checks import explain_compile_error

            paths = {uid: rec.path or uid for uid, rec in self.records.items()}
            explained = explain_compile_error(err, spec, paths)
            if explained is not None:  # an unreadable mesh: name the file and the link
                raise explained from err
            raise RuntimeError(f"MuJoCo could not compile the scene: {err}") from err
        for fn in self._post_compile:
            fn(model)
        return model


def light_diffuse(color: Any, intensity: float) -> list[float]:
    """Rendered diffuse colour of a light: ``color * intensity / 30``, clipped to 1."""
    scale = float(np.clip(float(intensity) / 30.0, 0.0, 1.0))
    return [float(np.clip(c * scale, 0.0, 1.0)) for c in list(color)[:3]]
