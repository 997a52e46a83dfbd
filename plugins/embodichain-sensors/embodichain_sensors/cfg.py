"""Sensor configs: ``CameraCfg``, ``StereoCameraCfg``, ``ContactSensorCfg``.

Field names and defaults follow EmbodiChain's ``lab.sim.sensors``. Conventions
(see docs/sensors.md): intrinsics are OpenCV pixels (pixel ``(u, v)`` has its
centre at integer coordinates, ``u`` right, ``v`` down); camera frames are
OpenGL/MuJoCo (look along -Z, +Y up, +X right); quaternions are ``(w, x, y, z)``.

Example:
    >>> cam = CameraCfg(uid="cam_high", width=960, height=540, intrinsics=(488.17, 488.17, 480, 270),
    ...                 extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1.2, 0, 1.6), target=(0.5, 0, 0.8)))
    >>> stereo = StereoCameraCfg(uid="eye_in_head", width=960, height=540, enable_depth=True,
    ...                          left_to_right_pos=(0.06, 0, 0), intrinsics=(450, 450, 480, 270),
    ...                          extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes"))
"""

from __future__ import annotations

import math
from typing import Any, List, Literal, Optional, Union

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import SensorCfg
from embodichain_core.utils.configclass import MISSING, configclass
from embodichain_sensors.renderer_choice import RENDERERS, choose_renderer

#: Largest image side accepted (pixels): MuJoCo's offscreen buffer is an OpenGL framebuffer.
MAX_IMAGE_SIDE = 16384
#: Bytes per pixel of each camera output (colour is RGBA uint8; depth/mask 4 bytes; normal/position 3 float32).
_BYTES_PER_PIXEL = {"color": 4, "depth": 4, "mask": 4, "normal": 12, "position": 12}


def _check_vector(value: Any, n: int, name: str) -> None:
    try:
        ok = len(value) == n and all(math.isfinite(float(v)) for v in value)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ConfigError(name, f"must be {n} finite numbers, got {value!r}")


def _check_intrinsics(value: object, name: str) -> None:
    """``(fx, fy, cx, cy)`` in pixels: fx, fy > 0 and a principal point cx, cy >= 0 (pixel
    coordinates from the image's top-left corner; a point beyond the image is allowed for
    off-centre crops)."""
    _check_vector(value, 4, name)
    fx, fy, cx, cy = (float(v) for v in value)  # type: ignore[attr-defined]
    if fx <= 0 or fy <= 0:
        raise ConfigError(name, f"fx and fy must be > 0 (pixels), got {value!r}")
    if cx < 0 or cy < 0:
        raise ConfigError(
            name,
            f"the principal point (cx, cy) = ({cx:g}, {cy:g}) must be >= 0 (pixels from the image's "
            f"top-left corner), got {value!r}",
        )


@configclass
class CameraCfg(SensorCfg):
    """A pinhole camera rendered with MuJoCo.

    Attributes:
        width, height: image size in pixels.
        near, far: clipping distances in metres (depth beyond ``far`` reads ``far``).
        intrinsics: ``(fx, fy, cx, cy)`` in pixels, honoured exactly.
        extrinsics: look-at (``eye``, ``target``, ``up``) or an offset (``pos``,
            ``quat``) from ``parent`` (a robot link, a body or a site; ``None``: the env frame).
        enable_*: which outputs :meth:`Camera.get_data` returns.
        renderer: ``"warp"`` (MuJoCo Warp's batched ray tracer: every env in one launch,
            on ``sim_cfg.backend: warp`` only), ``"opengl"`` (MuJoCo's OpenGL renderer, one
            env at a time, any backend) or ``None``: ``"warp"`` on the warp backend, else
            ``"opengl"`` (docs/sensors.md).
        render_threads: with ``renderer: "opengl"``, how many envs rasterize at once, each
            on its own OpenGL context and worker thread (``MUJOCO_GL`` egl or osmesa; the
            same images). ``1``: one context, on the calling thread; ``"auto"``: one per
            core but one (left to the recorder's writer), at most ``num_envs``.
    """

    @configclass
    class ExtrinsicsCfg:
        """Camera pose. With ``eye`` set the camera looks from ``eye`` at ``target``
        (``up`` defaults to +z), in the frame of ``parent`` (the env frame when
        ``parent`` is ``None``); otherwise ``pos``/``quat`` give the camera frame
        (OpenGL convention) in that frame."""

        pos: tuple = (0.0, 0.0, 0.0)
        quat: tuple = (1.0, 0.0, 0.0, 0.0)
        parent: Optional[str] = None
        eye: Optional[tuple] = None
        target: Optional[tuple] = None
        up: Optional[tuple] = None

        def __post_init__(self) -> None:
            _check_vector(self.pos, 3, "pos")
            _check_vector(self.quat, 4, "quat")
            if math.sqrt(sum(float(q) ** 2 for q in self.quat)) < 1e-9:
                raise ConfigError("quat", "must be a non-zero quaternion (w, x, y, z)")
            for name in ("eye", "target", "up"):
                if getattr(self, name) is not None:
                    _check_vector(getattr(self, name), 3, name)
            if (self.eye is None) != (self.target is None):
                raise ConfigError(
                    "target" if self.target is None else "eye", "look-at extrinsics need both 'eye' and 'target'"
                )

    sensor_type: str = "Camera"
    visualization_role: Literal["sensor", "record"] = "sensor"
    width: int = 640
    height: int = 480
    near: float = 0.005
    far: float = 100.0
    intrinsics: tuple = (600.0, 600.0, 320.0, 240.0)
    extrinsics: ExtrinsicsCfg = ExtrinsicsCfg()
    enable_color: bool = True
    enable_depth: bool = False
    enable_mask: bool = False
    enable_normal: bool = False
    enable_position: bool = False
    renderer: Optional[str] = None
    render_threads: Union[int, Literal["auto"]] = 1

    def __post_init__(self) -> None:
        threads = self.render_threads
        if threads != "auto" and (isinstance(threads, bool) or not isinstance(threads, int) or threads < 1):
            raise ConfigError("render_threads", f"must be an int >= 1 or 'auto', got {threads!r}")
        if self.renderer is not None and self.renderer not in RENDERERS:
            raise ConfigError(
                "renderer", f"must be one of {', '.join(map(repr, RENDERERS))} or None (auto), got {self.renderer!r}"
            )
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                raise ConfigError(name, f"must be a positive int, got {value!r}")
            if value > MAX_IMAGE_SIDE:
                raise ConfigError(
                    name, f"must be at most {MAX_IMAGE_SIDE} pixels (an OpenGL framebuffer side), got {value}"
                )
        if not (0.0 < float(self.near) < float(self.far)):
            raise ConfigError("near", f"need 0 < near < far, got near={self.near!r}, far={self.far!r}")
        _check_intrinsics(self.intrinsics, "intrinsics")

    def check_values(self, path: str, sim_cfg: Any) -> None:
        """Check what depends on the simulation settings, before the scene is built (the
        env's config validation calls it): the renderer must render this backend and device
        in one batch (:func:`~embodichain_sensors.renderer_choice.choose_renderer`).

        Args:
            path: this sensor's config path (``sensor[0]``).
            sim_cfg: the env's ``SimulationManagerCfg``.

        Raises:
            ConfigError: at ``<path>.renderer`` (or ``sim_cfg.render_cfg.quality``).
        """
        choose_renderer(sim_cfg, self.renderer, str(self.uid), path)

    def buffer_bytes_per_env(self) -> int:
        """Bytes of one env's images of one update: every enabled output of every view,
        plus the depth buffer the derived outputs are computed from (used by the
        core's memory estimate before the scene is built)."""
        wants = {
            "color": self.enable_color,
            "mask": self.enable_mask,
            "normal": self.enable_normal,
            "position": self.enable_position,
            "depth": self.enable_depth
            or self.enable_normal
            or self.enable_position
            or bool(getattr(self, "enable_disparity", False)),
        }
        per_pixel = sum(size for key, size in _BYTES_PER_PIXEL.items() if wants[key])
        per_pixel += 4 * bool(getattr(self, "enable_disparity", False))
        return int(self.width) * int(self.height) * per_pixel * self._views()

    def _views(self) -> int:
        """Images rendered per env (a stereo pair: 2)."""
        return 1

    @property
    def fx(self) -> float:
        """Focal length along u (pixels), from :attr:`intrinsics`."""
        return float(self.intrinsics[0])

    @property
    def fy(self) -> float:
        return float(self.intrinsics[1])

    @property
    def cx(self) -> float:
        return float(self.intrinsics[2])

    @property
    def cy(self) -> float:
        return float(self.intrinsics[3])


@configclass
class StereoCameraCfg(CameraCfg):
    """Two cameras of one size. The configured pose is the rig centre; the left
    camera sits at ``-left_to_right_pos / 2`` and the right camera at
    ``left_to_right_pos`` from the left one, rotated by ``left_to_right_rot``
    (extrinsic xyz Euler degrees), both in the left camera's frame.

    Attributes:
        intrinsics_right: the right camera's ``(fx, fy, cx, cy)``; ``None``: same as left.
        enable_disparity: output ``disparity = fx * |baseline| / depth`` (needs ``enable_depth``).
    """

    sensor_type: str = "StereoCamera"
    intrinsics_right: Optional[tuple] = None
    left_to_right_pos: tuple = (0.05, 0.0, 0.0)
    left_to_right_rot: tuple = (0.0, 0.0, 0.0)
    enable_disparity: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.intrinsics_right is not None:
            _check_intrinsics(self.intrinsics_right, "intrinsics_right")
        _check_vector(self.left_to_right_pos, 3, "left_to_right_pos")
        _check_vector(self.left_to_right_rot, 3, "left_to_right_rot")
        if self.enable_disparity and not self.enable_depth:
            raise ConfigError("enable_disparity", "disparity is computed from depth: set enable_depth=True")

    def _views(self) -> int:
        return 2

    def right_intrinsics(self) -> tuple:
        """The right camera's intrinsics (``intrinsics`` when not set)."""
        return tuple(self.intrinsics if self.intrinsics_right is None else self.intrinsics_right)


@configclass
class ArticulationContactFilterCfg:
    """Links of an articulation (or robot) a contact sensor watches; an empty
    ``link_name_list`` means every link. Link names may be regexes."""

    articulation_uid: str = MISSING
    link_name_list: List[str] = []


@configclass
class ContactSensorCfg(SensorCfg):
    """Contacts involving the listed rigid objects and articulation links.

    Attributes:
        rigid_uid_list: rigid objects (or backgrounds, groups) to watch.
        articulation_cfg_list: articulation/robot links to watch.
        filter_need_both_actor: keep a contact only when both sides are watched
            (else when either side is). With nothing listed every contact is kept.
        max_contacts_per_env: ``K``, the fixed size of the outputs ``(N, K, ...)``.
    """

    sensor_type: str = "ContactSensor"
    rigid_uid_list: List[str] = []
    articulation_cfg_list: List[ArticulationContactFilterCfg] = []
    filter_need_both_actor: bool = True
    max_contacts_per_env: int = 64

    def __post_init__(self) -> None:
        k = self.max_contacts_per_env
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise ConfigError("max_contacts_per_env", f"must be an int >= 1, got {k!r}")
