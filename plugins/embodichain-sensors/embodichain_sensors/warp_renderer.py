"""Batched camera rendering on the ``warp`` backend with MuJoCo Warp's ray tracer.

One :class:`WarpCameraRenderer` per camera sensor renders every view of every world in
one ``mujoco_warp.render`` launch, from the device state (no host copy), into torch tensors
on the sim device. It keeps the OpenGL path's conventions:

* **Intrinsics**: the primary rays are written from the sensor's ``(fx, fy, cx, cy)``
  (OpenCV pixels, pixel centres at integer coordinates), not from MuJoCo's camera
  model, so a ``set_intrinsics`` shows at the next update (one value for every env).
* **Extrinsics**: each view's pose is written into the worlds' ``cam_xpos``/``cam_xmat``
  before the launch, composed on the device from the mount body's pose in MuJoCo Warp's
  state (:class:`~embodichain_sensors.device_poses.DevicePoses`: the poses
  :meth:`Camera.get_view_poses` gives the OpenGL path, without a host round trip; cameras on
  moving links, ``set_local_pose`` and ``look_at`` included).
* **Images**: rows top-down; colour uint8 RGBA (alpha 255); depth float32 z-depth in
  metres, ``far`` where nothing is hit within ``far``; masks int32 entity ids, -1 none.

What the ray tracer does not render is refused (:class:`ConfigError`), never ignored:
``render_cfg.quality: high`` (reflections), per-env visual fields that MuJoCo Warp does not
hold (kept on the host for the OpenGL renderer, e.g. ``light_intensity``) and per-env
intrinsics. ``renderer: opengl`` on the camera renders those with OpenGL, one world at a time
(Warp's CPU device only: on a GPU it cannot batch, see :mod:`.renderer_choice`).
"""

from __future__ import annotations

from typing import Any, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_sensors.renderer_choice import choose_renderer, opengl_hint

__all__ = ["WarpCameraRenderer", "choose_renderer", "pixel_rays"]

_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)
#: Alpha 255 in the top byte of an int32 pixel.
_OPAQUE = -(1 << 24)


def pixel_rays(intrinsics: Sequence[float], width: int, height: int) -> np.ndarray:
    """Unit ray directions ``(H * W, 3)`` in the OpenGL camera frame, row-major from the
    top-left pixel, for OpenCV intrinsics ``(fx, fy, cx, cy)``."""
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    v, u = np.meshgrid(np.arange(height, dtype=np.float64), np.arange(width, dtype=np.float64), indexing="ij")
    rays = np.stack([(u - cx) / fx, -(v - cy) / fy, -np.ones_like(u)], axis=-1).reshape(-1, 3)
    return (rays / np.linalg.norm(rays, axis=1, keepdims=True)).astype(np.float32)


def _no_falloff(attenuation: torch.Tensor, falloff: torch.Tensor) -> None:
    """Zero attenuation (MuJoCo 4.0's default) means no falloff, as in the OpenGL path:
    write it as ``falloff`` = ``(1, 0, 0)`` (on the device), which the ray tracer reads that way."""
    if attenuation.numel():  # a select on the device, not a read of the mask
        zero = (attenuation == 0).all(dim=-1, keepdim=True)
        attenuation.copy_(torch.where(zero, falloff, attenuation))


class WarpCameraRenderer:
    """Every view of one camera sensor, for every world of a ``WarpSim``.

    Args:
        sim: the scene's :class:`~embodichain_core.sim.backend.warp_sim.WarpSim`.
        camera_ids: the MuJoCo camera of each view.
        width, height: image size.
        wants: ``{"color", "depth", "mask"}`` -> whether to render it.
        near, far: clipping distances (metres).
        where: config path of the sensor, for errors.
    """

    def __init__(
        self,
        sim: Any,
        camera_ids: Sequence[int],
        width: int,
        height: int,
        wants: dict[str, bool],
        near: float,
        far: float,
        where: str,
    ):
        self.sim, self.where = sim, where
        self._gpu = str(sim.wp_device).startswith("cuda")
        # numpy conversions where the backend's state is host memory (Warp's CPU device)
        self._numpy = bool(sim.capabilities.host_arrays)
        self.camera_ids = [int(c) for c in camera_ids]
        self.width, self.height = int(width), int(height)
        self.wants, self.near, self.far = dict(wants), float(near), float(far)
        wp, mjw = sim.wp, sim.mjw
        with wp.ScopedDevice(sim.wp_device):
            self.rc = mjw.create_render_context(
                sim.host_model,
                nworld=sim.num_envs,
                cam_res=(self.width, self.height),
                render_rgb=bool(wants["color"]),
                render_depth=bool(wants["depth"]),
                render_seg=bool(wants["mask"]),
                use_textures=True,
                use_shadows=False,
                cam_active=self.camera_ids,
                render_skybox=True,
                use_precomputed_rays=True,
            )
        self.rc.znear, self.rc.zfar = self.near, self.far  # read when the kernel is specialised
        self._rays = wp.to_torch(self.rc.ray)
        self._intrinsics: list[tuple] = [() for _ in self.camera_ids]
        dev = sim.device
        self._cam_xpos = wp.to_torch(sim.wp_data.cam_xpos)
        self._cam_xmat = wp.to_torch(sim.wp_data.cam_xmat)
        self._ids = torch.as_tensor(self.camera_ids, device=dev, dtype=torch.long)
        self._lut: torch.Tensor | None = None
        attenuation = wp.to_torch(sim.wp_model.light_attenuation)
        self._falloff = torch.tensor([1.0, 0.0, 0.0], dtype=attenuation.dtype, device=attenuation.device)

    # -- inputs ---------------------------------------------------------------------------------
    def check_supported(self) -> None:
        """Raise :class:`ConfigError` for per-env visual fields the ray tracer would not show."""
        host = self.sim.fields.unrendered_fields
        if host:
            raise ConfigError(
                self.where,
                f"model field {host[0]!r} has per-env values that MuJoCo Warp's renderer does not use on "
                f"backend 'warp' (only the OpenGL renderer reads it); randomize a field MuJoCo Warp batches "
                f"(light_diffuse, mat_rgba, geom_rgba...), or set {opengl_hint(self._gpu)}",
            )

    def set_intrinsics(self, view: int, intrinsics: np.ndarray) -> None:
        """Write view ``view``'s primary rays from ``(N, 4)`` intrinsics (one value for all envs)."""
        first = tuple(float(v) for v in intrinsics[0])
        if not np.allclose(intrinsics, np.asarray(first)[None]):
            raise ConfigError(
                self.where + ".intrinsics",
                "MuJoCo Warp's renderer traces one set of rays per camera for every world: per-env "
                f"intrinsics need {opengl_hint(self._gpu)}",
            )
        if first == self._intrinsics[view]:
            return
        n = self.width * self.height
        rays = torch.from_numpy(pixel_rays(first, self.width, self.height)).to(self._rays.device)
        self._rays[view * n : (view + 1) * n] = rays
        self._intrinsics[view] = first

    def set_poses(self, poses: Sequence[tuple[Any, Any]]) -> None:
        """Write each view's ``(pos (N, 3), rot (N, 3, 3))`` into the worlds' camera frames
        (tensors on the sim's device, or host arrays copied there)."""
        dev = self._cam_xpos.device
        pos = torch.stack([torch.as_tensor(p, device=dev) for p, _ in poses], dim=1)
        rot = torch.stack([torch.as_tensor(r, device=dev) for _, r in poses], dim=1)
        self._cam_xpos[:, self._ids] = pos.to(torch.float32)
        self._cam_xmat[:, self._ids] = rot.to(torch.float32)

    # -- rendering --------------------------------------------------------------------------------
    def render(self) -> None:
        """Refit the scene's bounding volumes and trace every view of every world (one launch)."""
        sim = self.sim
        _no_falloff(sim.wp.to_torch(sim.wp_model.light_attenuation), self._falloff)
        with sim.wp.ScopedDevice(sim.wp_device):
            sim.mjw.refit_bvh(sim.wp_model, sim.wp_data, self.rc)
            sim.mjw.render(sim.wp_model, sim.wp_data, self.rc)

    def update(self, views: Sequence[Any], poses: Sequence[tuple], ids: Any) -> dict[str, torch.Tensor]:
        """Render ``views`` (the camera's, with ``intrinsics`` and ``suffix``) at ``poses``;
        return the raw images by output key (``color``, ``depth``, ``mask`` + suffix)."""
        self.check_supported()
        for k, view in enumerate(views):
            self.set_intrinsics(k, view.intrinsics)
        self.set_poses(poses)
        self.render()
        raw: dict[str, torch.Tensor] = {}
        for k, view in enumerate(views):
            if self.wants["color"]:
                raw["color" + view.suffix] = self.color(k)
            if self.wants["depth"]:
                raw["depth" + view.suffix] = self.depth(k)
            if self.wants["mask"]:
                raw["mask" + view.suffix] = self.mask(k, ids.geom_to_id)
        return raw

    # The conversions run in numpy on the CPU (zero-copy views of Warp's buffers): torch's
    # intra-op threads cost ~8 ms per small elementwise op on a loaded 2-core machine, numpy
    # ~0.02 ms. On a GPU (and on the CPU device route, where the backend offers no host
    # views) they are torch ops on the device. The expressions serve both.
    def color(self, view: int) -> torch.Tensor:
        """``(N, H, W, 4)`` uint8 RGBA of view ``view`` (alpha 255)."""
        packed = self._slice(self.rc.rgb_data, view).contiguous()  # (N, H, W) uint32 ARGB
        argb = self._xp(packed.view(torch.int32))
        # whole-word integer ops (strided byte copies are ~10x slower): RGBA bytes, little-endian
        rgba = ((argb >> 16) & 0xFF) | (argb & 0xFF00) | ((argb & 0xFF) << 16) | _OPAQUE
        data = torch.from_numpy(rgba) if isinstance(rgba, np.ndarray) else rgba
        return data.view(torch.uint8).reshape(tuple(packed.shape) + (4,))

    def depth(self, view: int) -> torch.Tensor:
        """``(N, H, W)`` float32 z-depth in metres, ``far`` where nothing is hit."""
        z = self._slice(self.rc.depth_data, view)
        if self._numpy:
            zn = z.numpy()
            return torch.from_numpy(np.where((zn <= 0) | (zn > self.far), np.float32(self.far), zn))
        far = torch.tensor(self.far, dtype=z.dtype, device=z.device)
        return torch.where((z <= 0) | (z > far), far, z)

    def mask(self, view: int, geom_to_id: np.ndarray) -> torch.Tensor:
        """``(N, H, W)`` int32 entity ids (``geom_to_id`` of the hit geom), -1 where none."""
        seg = self._slice(self.rc.seg_data, view)  # (N, H, W, 2): object id, object type
        lut = np.append(np.asarray(geom_to_id, dtype=np.int32), np.int32(-1))  # index -1 -> -1
        if self._numpy:
            sn = seg.numpy()
            return torch.from_numpy(lut[np.where(sn[..., 1] == _GEOM, sn[..., 0], -1)])
        if self._lut is None:
            self._lut = torch.as_tensor(lut, device=seg.device)
        geom = torch.where(seg[..., 1] == _GEOM, seg[..., 0], torch.full_like(seg[..., 0], -1))
        return self._lut[geom.long()]

    def _xp(self, t: torch.Tensor) -> Any:
        """``t`` as a numpy view on the host route, else ``t``."""
        return t.numpy() if self._numpy else t

    def _slice(self, array: Any, view: int) -> torch.Tensor:
        """One view's pixels of a context buffer ``(nworld, views * H * W, ...)`` as ``(N, H, W, ...)``."""
        data = self.sim.wp.to_torch(array)
        n = self.width * self.height
        part = data[:, view * n : (view + 1) * n]
        return part.reshape((data.shape[0], self.height, self.width) + tuple(data.shape[2:]))
