"""Simulation and scene-object configs (the EmbodiChain ``lab.sim.cfg`` surface)."""

from __future__ import annotations

from typing import Any, Dict, List, Literal, Optional, Union, get_args

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.shapes import CubeCfg, ShapeCfg
from embodichain_core.utils.configclass import MISSING, configclass
from embodichain_core.utils.suggest import did_you_mean

#: Simulation backends of ``sim_cfg.backend`` (``run-env --backend``; docs/backends.md).
BackendName = Literal["mujoco_batch", "warp"]
BACKENDS: tuple[str, ...] = get_args(BackendName)


@configclass
class RenderCfg:
    """Renderer settings.

    Sensor cameras default to fast settings (no shadows, reflections or MSAA);
    ``quality="high"`` turns them on, for videos.
    """

    renderer: str = "auto"
    quality: Literal["fast", "high"] = "fast"
    spp: int = 1
    tone_mapping_enabled: bool = False
    tone_mapping_exposure: float = 1.0


@configclass
class PhysicsCfg:
    """Physics options mapped onto ``mjOption``."""

    gravity: tuple = (0.0, 0.0, -9.81)
    integrator: Literal["implicitfast", "implicit", "Euler", "RK4"] = "implicitfast"
    solver: Literal["Newton", "CG", "PGS"] = "Newton"
    iterations: int = 50
    cone: Literal["pyramidal", "elliptic"] = "pyramidal"
    #: MuJoCo's sleeping islands: resting bodies stop being simulated until something wakes
    #: them. Each body's ``sleep_threshold`` then applies (0: never sleeps); off by default.
    enable_sleep: bool = False
    enable_ccd: bool = False
    bounce_threshold: float = 2.0
    length_tolerance: float = 0.05
    speed_tolerance: float = 0.25


@configclass
class SimulationManagerCfg:
    """Simulation settings.

    ``physics_dt`` is the physics step the env's timing is defined on (EmbodiChain's
    meaning: control dt = physics_dt * sim_steps_per_control). MuJoCo integrates
    each physics step in ``physics_substeps`` substeps of ``physics_dt /
    physics_substeps`` for stiff drives; the default 0.01 / 5 gives MuJoCo 2 ms.
    """

    width: int = 1920
    height: int = 1080
    headless: bool = True
    #: With ``headless: false``: ``auto`` (a native window when a display exists, else the
    #: browser viewer), ``native``, ``browser`` or ``none`` (docs/viewer.md).
    viewer: Literal["auto", "native", "browser", "none"] = "auto"
    #: First localhost port the browser viewer tries (the next free one when taken).
    viewer_port: int = 8080
    render_cfg: RenderCfg = RenderCfg()
    gpu_id: int = 0
    thread_mode: int = 0
    cpu_num: int = 0
    num_envs: int = 1
    arena_space: float = 5.0
    physics_dt: float = 0.01
    physics_substeps: int = 5
    sim_device: str = "cpu"
    #: ``"mujoco_batch"`` (CPU threads, float64) or ``"warp"`` (MuJoCo Warp on ``sim_device``
    #: cpu/cuda, float32; docs/backends.md).
    backend: BackendName = "mujoco_batch"
    physics_config: PhysicsCfg = PhysicsCfg()
    persistent: bool = True
    #: Raised plausibility bounds, ``{"position" | "mass" | "density" | "friction": bound}``
    #: (defaults in :data:`embodichain_core.config.plausible.DEFAULT_LIMITS`).
    physical_limits: Optional[Dict[str, float]] = None


@configclass
class ObjectBaseCfg:
    """Common fields: ``uid`` and the initial pose (Euler degrees, extrinsic xyz)."""

    uid: Optional[str] = None
    init_pos: tuple = (0.0, 0.0, 0.0)
    init_rot: tuple = (0.0, 0.0, 0.0)
    init_local_pose: Optional[List[List[float]]] = None


@configclass
class RigidBodyAttributesCfg:
    """Physical attributes of a rigid body (PhysX names, mapped onto MuJoCo).

    ``mass`` 0 means "from density". Friction uses ``static_friction`` as MuJoCo's
    sliding coefficient; damping becomes free-joint dof damping.
    """

    mass: float = 1.0
    density: float = 1000.0
    angular_damping: float = 0.7
    linear_damping: float = 0.7
    max_depenetration_velocity: float = 10.0
    sleep_threshold: float = 0.001
    min_position_iters: int = 4
    min_velocity_iters: int = 1
    max_linear_velocity: float = 100.0
    max_angular_velocity: float = 100.0
    enable_ccd: bool = False
    contact_offset: float = 0.002
    rest_offset: float = 0.0
    enable_collision: bool = True
    restitution: float = 0.0
    dynamic_friction: float = 0.5
    static_friction: float = 0.5


@configclass
class RigidObjectCfg(ObjectBaseCfg):
    """A rigid body: primitive or mesh, dynamic or kinematic/static."""

    shape: ShapeCfg = CubeCfg(size=[0.05, 0.05, 0.05])
    attrs: RigidBodyAttributesCfg = RigidBodyAttributesCfg()
    body_type: Literal["dynamic", "kinematic", "static"] = "dynamic"
    max_convex_hull_num: Optional[int] = None
    acd_method: Optional[str] = None
    sdf_resolution: Optional[int] = None
    body_scale: tuple = (1.0, 1.0, 1.0)
    use_usd_properties: bool = False


@configclass
class RigidObjectGroupCfg:
    """Rigid objects managed together (``uid/<name>`` each)."""

    uid: str = MISSING
    rigid_objects: Dict[str, RigidObjectCfg] = {}
    body_type: Literal["dynamic", "kinematic"] = "dynamic"
    folder_path: Optional[str] = None
    max_num: int = 1
    ext: str = ".obj"


@configclass
class JointDrivePropertiesCfg:
    """Joint drives. Each value is a number or ``{joint-regex: number}``.

    ``drive_type="force"`` makes a PD drive (MuJoCo actuators: ``kp=stiffness``,
    ``kv=damping``, the joint's actuator force clamped to ``max_effort``);
    ``"none"`` leaves the joints passive.
    """

    drive_type: Literal["force", "acceleration", "none"] = "force"
    stiffness: Union[float, Dict[str, float]] = 1e4
    damping: Union[float, Dict[str, float]] = 1e3
    max_effort: Union[float, Dict[str, float]] = 1e10
    max_velocity: Union[float, Dict[str, float]] = 1e10
    friction: Union[float, Dict[str, float]] = 0.0
    armature: Union[float, Dict[str, float]] = 0.0


@configclass
class ArticulationCfg(ObjectBaseCfg):
    """A jointed object from URDF or MJCF (``fpath``) or inline MJCF (``mjcf``).

    ``keep_actuators``: keep the actuators the model file declares (its position and
    velocity servos then act as the joints' drives; other joints get ``drive_pros``
    drives). By default they are replaced by the ``drive_pros`` drives, with one notice
    naming them. Link inertias that break MuJoCo's triangle inequality are balanced
    (one warning names the links).
    """

    fpath: Optional[str] = None
    mjcf: Optional[str] = None
    keep_actuators: bool = False
    drive_pros: JointDrivePropertiesCfg = JointDrivePropertiesCfg(drive_type="none")
    body_scale: tuple = (1.0, 1.0, 1.0)
    attrs: RigidBodyAttributesCfg = RigidBodyAttributesCfg()
    link_attrs: Dict[str, Any] = {}
    fix_base: bool = True
    disable_self_collision: bool = True
    init_qpos: Optional[List[float]] = None
    qpos_limits: Optional[Any] = None
    sleep_threshold: float = 0.005
    min_position_iters: int = 4
    min_velocity_iters: int = 1
    build_pk_chain: bool = True
    compute_uv: bool = False
    use_usd_properties: bool = False

    def build_spec(self) -> Any:
        """Return the ``mujoco.MjSpec`` of this articulation (loaded from the cfg)."""
        from embodichain_core.sim.scene_build.model_source import spec_from_cfg

        return spec_from_cfg(self)


@configclass
class RobotCfg(ArticulationCfg):
    """An articulation the env controls, with named control parts.

    ``control_parts`` maps a part name to joint-name regexes. ``solver_cfg`` maps a
    part to its kinematics solver settings, ``{part: {"class_type": name, ...}}``, with
    ``name`` a solver class registered by a plugin (``DLSSolver`` from
    embodichain-robots); see :mod:`embodichain_core.sim.entities.solvers`. Robot plugins
    subclass this and override :meth:`build_spec` to generate their model.
    """

    drive_pros: JointDrivePropertiesCfg = JointDrivePropertiesCfg()
    control_parts: Optional[Dict[str, List[str]]] = None
    urdf_cfg: Optional[Any] = None
    solver_cfg: Optional[Any] = None
    workspace_cfg: Optional[Any] = None
    gravity_compensation: bool = True
    class_type: Optional[str] = None
    robot_type: Optional[str] = None

    @classmethod
    def _resolve_subclass(cls, data: dict, path: str) -> type:
        name = data.get("class_type") or data.get("robot_type")
        if cls is not RobotCfg or not name:
            return cls
        from embodichain_core.plugins import AmbiguousNameError, get_robot_cfg_class, robot_registry

        try:
            return get_robot_cfg_class(str(name))
        except AmbiguousNameError as err:  # several plugins register the name: no silent choice
            raise ConfigError(f"{path}.class_type" if path else "class_type", str(err)) from None
        except KeyError:
            if data.get("fpath") or data.get("mjcf"):
                return cls
            where = f"{path}.class_type" if path else "class_type"
            reason = f"unknown robot {name!r}.{did_you_mean(str(name), robot_registry().names())}"
            raise ConfigError(where, reason) from None


@configclass
class LightCfg(ObjectBaseCfg):
    """A light. ``point`` and ``spot`` lights are per env; ``sun``/``direction`` global.

    ``intensity`` follows EmbodiChain's scale: the rendered diffuse colour is
    ``color * intensity / 30`` (clipped to 1).
    """

    light_type: Literal["point", "spot", "sun", "direction", "directional", "rect", "mesh"] = "point"
    color: tuple = (1.0, 1.0, 1.0)
    intensity: float = 30.0
    enable_shadow: bool = True
    radius: float = 10.0
    direction: tuple = (0.0, 0.0, -1.0)
    angular_radius: float = 0.0
    halo_size: float = 0.0
    halo_falloff: float = 0.0
    spot_angle_inner: float = 30.0
    spot_angle_outer: float = 45.0
    rect_width: float = 1.0
    rect_height: float = 1.0
    mesh_path: Optional[str] = None


@configclass
class SensorCfg(ObjectBaseCfg):
    """Base of sensor configs; ``sensor_type`` picks the registered sensor type."""

    sensor_type: str = ""

    @configclass
    class OffsetCfg:
        pos: tuple = (0.0, 0.0, 0.0)
        quat: tuple = (1.0, 0.0, 0.0, 0.0)
        parent: Optional[str] = None

    @classmethod
    def _resolve_subclass(cls, data: dict, path: str) -> type:
        name = data.get("sensor_type")
        if not name:
            if cls is SensorCfg:
                raise ConfigError(path, "a sensor needs a 'sensor_type'")
            return cls
        from embodichain_core.plugins import AmbiguousNameError, get_sensor_classes, sensor_registry

        try:
            return get_sensor_classes(str(name))[0]
        except AmbiguousNameError as err:  # several plugins register the name: no silent choice
            raise ConfigError(f"{path}.sensor_type" if path else "sensor_type", str(err)) from None
        except KeyError:
            where = f"{path}.sensor_type" if path else "sensor_type"
            reason = f"unknown sensor type {name!r}.{did_you_mean(str(name), sensor_registry().names())}"
            raise ConfigError(where, reason) from None
