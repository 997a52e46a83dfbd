"""``Camera``: a batched pinhole camera sensor rendered with MuJoCo.

With ``renderer: opengl`` one :class:`~embodichain_sensors.renderer.SensorRenderer`
per sensor, created on the first update and reused: N envs cost N renders (each from
env ``i``'s model and data, so per-env light and material changes show). With
``renderer: warp`` (the default on ``sim_cfg.backend: warp``) one
:class:`~embodichain_sensors.warp_renderer.WarpCameraRenderer` traces every env and
view in one launch on the sim device; outputs are then tensors on that device.
Outputs (``N`` envs):

=============  ===========================  ==========================================
key            dtype / shape                meaning
=============  ===========================  ==========================================
``color``      uint8 ``(N, H, W, 4)``       RGBA, alpha 255
``depth``      float32 ``(N, H, W)``        z-depth in metres (``far`` where empty)
``mask``       int32 ``(N, H, W)``          entity id (:meth:`uid_of_mask_id`), -1 none
``normal``     float32 ``(N, H, W, 3)``     unit normals, camera frame (from depth)
``position``   float32 ``(N, H, W, 3)``     points, camera frame (OpenGL: -Z forward)
=============  ===========================  ==========================================

Example:
    >>> cam = env.sensors["cam"]  # doctest: +SKIP
    >>> rgb = obs["sensor"]["cam"]["color"][..., :3]
    >>> K = cam.get_intrinsics()          # (N, 3, 3)
    >>> pose = cam.get_arena_pose()       # (N, 7) in the env frame
"""

from __future__ import annotations

import warnings
from typing import Any, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.rendering import THREADED_BACKENDS, gl_backend
from embodichain_core.sim.sensor_base import BaseSensor
from embodichain_core.utils.math import compose_frames
from embodichain_sensors import geometry as geo
from embodichain_sensors.camera_arrays import _add_spec_camera, _alloc, _host, _tensor, _trailing
from embodichain_sensors.camera_poses import CameraPoses, View
from embodichain_sensors.device_poses import DevicePoses
from embodichain_sensors.envs import EnvReader
from embodichain_sensors.ids import EntityIds
from embodichain_sensors.mount import Mount, resolve_mount
from embodichain_sensors.render_pool import RenderPool, render_thread_count
from embodichain_sensors.renderer import SensorRenderer
from embodichain_sensors.renderer_choice import choose_renderer
from embodichain_sensors.warp_renderer import WarpCameraRenderer


class Camera(CameraPoses, BaseSensor):
    """A camera of the scene (see the module docstring for its outputs)."""

    image_dims: dict[str, int] = {"depth": 0, "mask": 0}  # extra trailing dims of HxW outputs

    def __init__(self, cfg: Any, scene: Any):
        super().__init__(cfg, scene)
        self.num_envs = int(scene.num_envs)
        self.mount = Mount()
        self._local_pos, self._local_rot = self._initial_local_pose()
        self.views = self._make_views()
        self._renderer: Optional[SensorRenderer] = None
        self._pool: Optional[RenderPool] = None
        self._threaded = False  # the GL backend hands contexts between threads (set by bind)
        self._warp: Optional[WarpCameraRenderer] = None
        self._device_poses = DevicePoses()
        self._path = f"sensor {self.uid!r}"
        self._ids: Optional[EntityIds] = None
        self._data: dict[str, torch.Tensor] = {}
        self._envs = EnvReader(scene)

    # -- construction ---------------------------------------------------------------------
    def _make_views(self) -> list[View]:
        intr = np.tile(np.asarray(self.cfg.intrinsics, dtype=np.float64), (self.num_envs, 1))
        return [View("", intr, np.zeros(3), np.eye(3))]

    def build(self, builder: Any) -> None:
        """Resolve the parent and add one MuJoCo camera per view to the spec."""
        cfg, spec = self.cfg, builder.spec
        path = getattr(builder.records.get(self.uid), "path", "")  # claimed with its config path (sensor[0])
        self._path = path or self._path
        where = f"{path}.extrinsics.parent" if path else f"sensor {self.uid!r}: extrinsics.parent"
        try:
            self.mount = resolve_mount(spec, cfg.extrinsics.parent, builder.records, where)
        except ConfigError as err:  # name the sensor too, next to its config path
            raise ConfigError(err.path, f"sensor {self.uid!r}: {err.reason}") from err
        body = spec.worldbody if self.mount.body is None else spec.body(self.mount.body)
        for k, view in enumerate(self.views):
            view.camera = self.uid if len(self.views) == 1 else f"{self.uid}/{('left', 'right')[k]}"
            rig = compose_frames(self.mount.pos, self.mount.rot, self._local_pos[0], self._local_rot[0])
            pos, rot = compose_frames(*rig, view.pos, view.rot)
            _add_spec_camera(body, view.camera, pos, rot, view.intrinsics[0], cfg.width, cfg.height)
        glob = spec.visual.global_
        glob.offwidth, glob.offheight = max(glob.offwidth, cfg.width), max(glob.offheight, cfg.height)

    def bind(self) -> None:
        """Find the mount body and cameras in the compiled model; build the id table."""
        model = self.scene.model
        self.mount.bind(model)
        for view in self.views:
            view.camera_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, view.camera)
        self._ids = EntityIds.from_scene(self.scene)
        self.renderer_name = self._check_renderer()

    def _check_renderer(self) -> str:
        """The renderer in effect (see ``CameraCfg.renderer``); what it cannot do raises here."""
        chosen = choose_renderer(self.scene.sim_cfg, getattr(self.cfg, "renderer", None), self.uid, self._path)
        setting = getattr(self.cfg, "render_threads", 1)  # "auto" falls back to one thread silently
        backend = gl_backend()
        self._threaded = backend in THREADED_BACKENDS
        if (
            chosen == "opengl"
            and setting != "auto"
            and render_thread_count(setting, self.num_envs) > 1
            and not self._threaded
        ):
            warnings.warn(
                f"{self._path}.render_threads = {setting}: rendering on one thread, since MUJOCO_GL "
                f"{backend!r} cannot hand an OpenGL context between threads (use "
                f"{' or '.join(THREADED_BACKENDS)} for parallel rendering)",
                stacklevel=2,
            )
        return chosen

    # -- rendering -------------------------------------------------------------------------
    @property
    def renderer(self) -> SensorRenderer:
        """The sensor's renderer (created on first use; raises when no GL backend works)."""
        if self._renderer is None:
            self._renderer = self._new_renderer()
        return self._renderer

    def _new_renderer(self) -> SensorRenderer:
        quality = getattr(getattr(self.scene.sim_cfg, "render_cfg", None), "quality", "fast")
        return SensorRenderer(self.scene.model, self.cfg.width, self.cfg.height, quality=quality)

    def _wants(self) -> dict[str, bool]:
        cfg = self.cfg
        geometric = cfg.enable_normal or cfg.enable_position
        return {
            "color": cfg.enable_color,
            "depth": cfg.enable_depth or geometric or getattr(cfg, "enable_disparity", False),
            "mask": cfg.enable_mask,
        }

    def update(self) -> None:
        """Render every env and every view; results go to :meth:`get_data`."""
        if getattr(self, "renderer_name", "opengl") == "warp":
            self._update_warp()
            return
        wants, (n, h, w) = self._wants(), (self.num_envs, self.cfg.height, self.cfg.width)
        raw = {f"{key}{v.suffix}": _alloc(key, n, h, w) for v in self.views for key, on in wants.items() if on}
        poses = self.get_view_poses()
        pool = self._render_pool()
        if pool is None:
            renderer = self.renderer
            renderer.make_current()
            for i in range(n):
                self._prepare_env(renderer, i, poses)
                self._render_env(renderer, i, poses, wants, raw)
        else:
            pool.run(
                n,
                lambda r, i: self._prepare_env(r, i, poses),
                lambda r, i: self._render_env(r, i, poses, wants, raw),
            )
        self._data = self._outputs(raw)

    def _prepare_env(self, renderer: SensorRenderer, i: int, poses: list) -> None:
        """Env ``i``'s scene from the first view's camera (one scene update for all views;
        the camera first: MuJoCo places the ground patch from it)."""
        view, (pos, rot) = self.views[0], poses[0]
        renderer.set_camera(pos[i], rot[i], view.intrinsics[i], self.cfg.near, self.cfg.far)
        renderer.update_scene(self._envs.model(i), self._envs.data(i), view.camera_id)

    def _render_env(self, renderer: SensorRenderer, i: int, poses: list, wants: dict, raw: dict) -> None:
        """Every view of env ``i`` (only the camera moves between views)."""
        for k, (view, (pos, rot)) in enumerate(zip(self.views, poses)):
            if k:
                renderer.set_camera(pos[i], rot[i], view.intrinsics[i], self.cfg.near, self.cfg.far)
            self._render_view(renderer, view.suffix, i, wants, raw)

    def _render_pool(self) -> Optional[RenderPool]:
        """The pool of ``render_threads`` renderers (``None``: one renderer, this thread)."""
        threads = render_thread_count(getattr(self.cfg, "render_threads", 1), self.num_envs)
        if threads <= 1 or not self._threaded:
            return None
        if self._pool is not None and self._pool.threads != threads:  # render_threads changed
            self._pool.close()
            self._pool = None
        if self._pool is None:
            self._pool = RenderPool(self._new_renderer, threads)
        return self._pool

    @property
    def warp_renderer(self) -> WarpCameraRenderer:
        """The batched renderer of ``renderer: warp`` (created on first use; compiles once)."""
        if self._warp is None:
            cfg = self.cfg
            self._warp = WarpCameraRenderer(
                self.scene.sim,
                [v.camera_id for v in self.views],
                cfg.width,
                cfg.height,
                self._wants(),
                cfg.near,
                cfg.far,
                f"{self._path}.renderer",
            )
        return self._warp

    def _update_warp(self) -> None:
        """Every env and view in one MuJoCo Warp launch, from the device state."""
        renderer = self.warp_renderer
        self._data = self._outputs(renderer.update(self.views, self._device_poses(self), self._bound_ids()))

    def _render_view(self, renderer: SensorRenderer, sfx: str, i: int, wants: dict, raw: dict) -> None:
        rgb, depth = renderer.render(color=wants["color"], depth=wants["depth"])
        if rgb is not None:  # rows flipped (OpenGL is bottom-up); one channel at a time is
            dst, src = raw["color" + sfx][i], rgb[::-1]  # ~10x faster than a (..., :3) copy
            for c in range(3):
                dst[:, :, c] = src[:, :, c]
        if depth is not None:
            raw["depth" + sfx][i] = depth[::-1]
        if wants["mask"]:
            raw["mask" + sfx][i] = renderer.render_segmentation(self._bound_ids().geom_to_id)[::-1]

    def _outputs(self, raw: dict[str, Any]) -> dict[str, torch.Tensor]:
        """Requested outputs (with the derived ones) as tensors (numpy images, or tensors of
        the warp renderer on the sim device; derived outputs are computed on the host)."""
        cfg, out = self.cfg, {}
        for view in self.views:
            sfx = view.suffix
            if cfg.enable_color:
                out["color" + sfx] = raw["color" + sfx]
            if cfg.enable_depth:
                out["depth" + sfx] = _trailing(raw["depth" + sfx], self.image_dims["depth"])
            if cfg.enable_mask:
                out["mask" + sfx] = _trailing(raw["mask" + sfx], self.image_dims["mask"])
            if cfg.enable_position or cfg.enable_normal:
                self._geometric(out, sfx, _host(raw["depth" + sfx]), view.intrinsics)
        return {k: _tensor(v, self._out_device) for k, v in out.items()}

    @property
    def _out_device(self) -> torch.device:
        """Where outputs live: the sim device with the warp renderer, else the CPU."""
        return self.scene.sim.device if self._warp is not None else torch.device("cpu")

    def _geometric(self, out: dict, sfx: str, depth: np.ndarray, intrinsics: np.ndarray) -> None:
        points = np.stack([geo.depth_to_points(depth[i], intrinsics[i]) for i in range(self.num_envs)])
        empty = (depth >= np.float32(self.cfg.far) * np.float32(0.9999))[..., None]
        if self.cfg.enable_position:
            out["position" + sfx] = np.where(empty, np.float32(0), points)
        if self.cfg.enable_normal:
            out["normal" + sfx] = np.where(empty, np.float32(0), geo.points_to_normals(points))

    def get_data(self) -> dict[str, torch.Tensor]:
        """``{name: tensor (N, ...)}`` of the last :meth:`update` (rendering now if none)."""
        if not self._data:
            self.update()
        return self._data

    # -- ids and lifecycle ------------------------------------------------------------------------
    @property
    def mask_id_table(self) -> dict[int, str]:
        """``{mask id: entity uid}`` (``-1`` in a mask means no entity)."""
        return self._bound_ids().as_dict()

    def uid_of_mask_id(self, mask_id: int) -> Optional[str]:
        """The entity uid of a mask value (``None`` for ``-1``)."""
        return self._bound_ids().uid_of_id(mask_id)

    def mask_id_of(self, uid: str) -> int:
        """The mask value of entity ``uid``."""
        return self._bound_ids().id_of_uid(uid)

    def _bound_ids(self) -> EntityIds:
        if self._ids is None:
            raise RuntimeError(f"sensor {self.uid!r}: mask ids exist once the scene is built")
        return self._ids

    def reset(self, env_ids: Any = None) -> None:
        """Nothing per env to clear (poses persist across resets, as in EmbodiChain)."""

    def close(self) -> None:
        self._warp = None
        if self._pool is not None:
            self._pool.close()
            self._pool = None
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
