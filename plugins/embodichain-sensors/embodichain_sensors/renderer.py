"""The offscreen renderer of the camera sensors: one per sensor, reused for every env.

It holds what ``mujoco.Renderer`` holds (a GL context, an ``MjrContext``, an
``MjvScene``) and renders the way the sensors need:

* the projection is set from ``(fx, fy, cx, cy)`` and ``near``/``far`` on the
  scene camera after ``mjv_updateScene`` (an off-centre OpenGL frustum), so the
  principal point and the clipping planes are exact for any model;
* colour and depth come from one render (``mjr_readPixels`` reads both);
* segmentation is a second render with ``mjRND_SEGMENT | mjRND_IDCOLOR``;
* fast settings by default: no shadows, no reflections, no MSAA;
* its GL context can be handed to another thread (:meth:`SensorRenderer.release_current`,
  then :meth:`SensorRenderer.current` there): the render pool of ``render_threads`` does.

Its GL objects are freed in its own GL context, by :meth:`close` or when it is
garbage-collected: OpenGL object names are per context and every context numbers
them from 1, so freeing them in whichever context is current would delete another
renderer's textures, meshes and framebuffer.

Example:
    >>> r = SensorRenderer(model, 640, 480)  # doctest: +SKIP
    >>> r.update_scene(env_model, env_data)
    >>> r.set_camera(pos, rot, (600, 600, 320, 240), near=0.01, far=10.0)
    >>> rgb, depth = r.render(color=True, depth=True)
"""

from __future__ import annotations

import atexit
import weakref
from typing import Any, ContextManager, Optional, Sequence

import mujoco
import numpy as np

from embodichain_core.rendering import create_gl_context, release_current
from embodichain_sensors.geometry import frustum

_FLAGS = mujoco.mjtRndFlag
_POINT, _SPOT = mujoco.mjtLightType.mjLIGHT_POINT, mujoco.mjtLightType.mjLIGHT_SPOT
_OPEN: "weakref.WeakSet[SensorRenderer]" = weakref.WeakSet()
_EXIT_HOOK: list[bool] = []  # [True] once _close_all is registered with atexit


class SensorRenderer:
    """Offscreen rendering of ``width x height`` images of one model.

    Args:
        model: the compiled scene model (its textures and meshes are uploaded once).
        width, height: image size; grows the model's offscreen buffer if needed.
        quality: ``"fast"`` (no shadows, reflections, MSAA) or ``"high"``.
        max_geom: scene capacity.
    """

    def __init__(self, model: mujoco.MjModel, width: int, height: int, quality: str = "fast", max_geom: int = 10000):
        self.width, self.height, self.quality = int(width), int(height), quality
        self._gl: Optional[Any] = create_gl_context(self.width, self.height)
        try:
            self.context = self._make_context(model)
        except BaseException:
            self._gl.free()
            raise
        # close() or garbage collection, whichever comes first (at exit: _close_all)
        self._release = weakref.finalize(self, _release_gl, self._gl, self.context)
        self._release.atexit = False
        _track(self)
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom)
        high = quality == "high"
        self.scene.flags[_FLAGS.mjRND_SHADOW] = high
        self.scene.flags[_FLAGS.mjRND_REFLECTION] = high
        self.option = mujoco.MjvOption()
        self.option.sitegroup[:] = 0  # sites are markers, not scene content
        self.camera = mujoco.MjvCamera()
        self._rect = mujoco.MjrRect(0, 0, self.width, self.height)
        self._rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self._depth = np.empty((self.height, self.width), dtype=np.float32)
        self._near_far = (0.01, 100.0)
        self._gl_camera: Optional[tuple] = None
        self._camera_dirty = False

    def _make_context(self, model: mujoco.MjModel) -> mujoco.MjrContext:
        vis = model.vis
        size = (vis.global_.offwidth, vis.global_.offheight, vis.quality.offsamples)
        vis.global_.offwidth = max(size[0], self.width)
        vis.global_.offheight = max(size[1], self.height)
        if self.quality != "high":
            vis.quality.offsamples = 0  # no MSAA buffer for this context only
        try:
            context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        finally:
            vis.global_.offwidth, vis.global_.offheight, vis.quality.offsamples = size
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, context)
        context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        return context

    def make_current(self) -> None:
        """Bind this renderer's GL context (once per batch of renders)."""
        if self._gl is None:
            raise RuntimeError("the renderer is closed")
        self._gl.make_current()

    def release_current(self) -> None:
        """Unbind this renderer's GL context from this thread, for :meth:`current` elsewhere."""
        self.make_current()
        release_current()

    def current(self) -> ContextManager[Any]:
        """This renderer's GL context bound on this thread for a ``with`` block (unbound after
        it when no context was current before)."""
        if self._gl is None:
            raise RuntimeError("the renderer is closed")
        return self._gl.as_current()

    def update_scene(self, model: mujoco.MjModel, data: mujoco.MjData, camera_id: int = -1) -> None:
        """Fill the scene from ``model`` and ``data`` (one env's; per-env colours show).

        The camera of :meth:`set_camera` is applied before and after
        ``mjv_updateScene``: MuJoCo places the ground plane's patch and the headlight
        from the scene camera it finds, so the image must not depend on the
        previous frame's camera.
        """
        cam = self.camera
        cam.type = mujoco.mjtCamera.mjCAMERA_FIXED if camera_id >= 0 else mujoco.mjtCamera.mjCAMERA_FREE
        cam.fixedcamid = int(camera_id)
        self._apply_camera()
        mujoco.mjv_updateScene(model, data, self.option, None, cam, mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        self._apply_camera()
        self._adapt_lights()

    def _adapt_lights(self) -> None:
        """Make point lights light the classic OpenGL renderer (MuJoCo 4.0 skips
        ``mjLIGHT_POINT`` there): an omnidirectional spot (cutoff 180) is the OpenGL
        point light. A zero attenuation (4.0's default) means no falloff."""
        scene = self.scene
        for light in scene.lights[: scene.nlight]:
            if light.headlight:
                continue
            if light.type == _POINT:
                light.type, light.cutoff, light.exponent = _SPOT, 180.0, 0.0
            if not light.attenuation.any():
                light.attenuation[:] = (1.0, 0.0, 0.0)

    def set_camera(
        self, pos: np.ndarray, rot: np.ndarray, intrinsics: Sequence[float], near: float, far: float
    ) -> None:
        """Render from ``pos``/``rot`` (OpenGL camera frame) with exact intrinsics."""
        center, half_width, bottom, top = frustum(intrinsics, self.width, self.height, near)
        self._gl_camera = (
            np.asarray(pos, dtype=np.float32),
            np.asarray(rot, dtype=np.float32),
            (center, half_width, bottom, top, float(near), float(far)),
        )
        self._near_far = (float(near), float(far))
        self._camera_dirty = True  # applied by the next update_scene or render

    def _apply_camera(self) -> None:
        self._camera_dirty = False
        if self._gl_camera is None:
            return
        pos, rot, (center, half_width, bottom, top, near, far) = self._gl_camera
        for cam in (self.scene.camera[0], self.scene.camera[1]):
            cam.pos[:] = pos
            cam.forward[:] = -rot[:, 2]
            cam.up[:] = rot[:, 1]
            cam.frustum_center, cam.frustum_width = center, half_width
            cam.frustum_bottom, cam.frustum_top = bottom, top
            cam.frustum_near, cam.frustum_far = near, far
            cam.orthographic = 0

    def render(self, color: bool = True, depth: bool = False) -> tuple[Optional[np.ndarray], Optional[np.ndarray]]:
        """Render once; return ``(rgb (H, W, 3) uint8, depth (H, W) float32 metres)``.

        Rows are bottom-up (OpenGL order): index ``[::-1]`` for the image. The
        arrays are reused by the next call; copy them out.
        """
        if self._camera_dirty:
            self._apply_camera()
        mujoco.mjr_render(self._rect, self.scene, self.context)
        mujoco.mjr_readPixels(self._rgb if color else None, self._depth if depth else None, self._rect, self.context)
        if depth:
            near, far = self._near_far
            # reversed-Z depth buffer (1 at near, 0 at far) -> z-depth in metres
            z = self._depth
            np.multiply(z, np.float32(far - near), out=z)
            np.add(z, np.float32(near), out=z)
            np.divide(np.float32(far * near), z, out=z)
        return (self._rgb if color else None), (self._depth if depth else None)

    def render_segmentation(self, geom_to_id: np.ndarray) -> np.ndarray:
        """Render object ids: ``geom_to_id[geom]`` per pixel, ``-1`` where no geom.

        Returns ``(H, W)`` int32, rows bottom-up like :meth:`render`.
        """
        if self._camera_dirty:
            self._apply_camera()
        flags = self.scene.flags
        saved = flags.copy()
        flags[_FLAGS.mjRND_SEGMENT] = flags[_FLAGS.mjRND_IDCOLOR] = 1
        flags[_FLAGS.mjRND_SHADOW] = flags[_FLAGS.mjRND_REFLECTION] = 0
        try:
            mujoco.mjr_render(self._rect, self.scene, self.context)
            mujoco.mjr_readPixels(self._rgb, None, self._rect, self.context)
        finally:
            flags[:] = saved
        return self._segment_lut(geom_to_id)[self._segids()]

    def _segids(self) -> np.ndarray:
        rgb = self._rgb
        if self.scene.ngeom < 255:
            return rgb[..., 0]
        return rgb[..., 0].astype(np.int32) | (rgb[..., 1].astype(np.int32) << 8) | (rgb[..., 2].astype(np.int32) << 16)

    def _segment_lut(self, geom_to_id: np.ndarray) -> np.ndarray:
        """Segment colour (scene ``segid + 1``) -> object id, ``-1`` for the background."""
        n = self.scene.ngeom
        lut = np.full(max(n + 1, 256), -1, dtype=np.int32)
        geom_type = int(mujoco.mjtObj.mjOBJ_GEOM)
        for g in self.scene.geoms[:n]:
            if g.objtype == geom_type and g.segid >= 0:
                lut[g.segid + 1] = geom_to_id[g.objid]
        return lut

    def close(self) -> None:
        """Free the GL resources; idempotent."""
        self._gl = None
        self._release()
        _OPEN.discard(self)

    def __enter__(self) -> "SensorRenderer":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _release_gl(gl: Any, context: mujoco.MjrContext) -> None:
    """Free ``context``'s GL objects inside ``gl`` (the context that made them), then ``gl``.

    The context current before stays current: a renderer collected in the middle of
    another one's frame must leave that renderer bound and its objects intact.
    """
    try:
        with gl.as_current():
            context.free()
    finally:
        gl.free()


def _track(renderer: SensorRenderer) -> None:
    """Close ``renderer`` at exit if it is still open. The hook is registered after the
    first GL context exists, so it runs before the GL backend's own exit hook (which
    terminates the EGL display) and every renderer is freed in its live context."""
    if not _EXIT_HOOK:
        atexit.register(_close_all)
        _EXIT_HOOK.append(True)
    _OPEN.add(renderer)


def _close_all() -> None:
    """Free every open renderer at interpreter exit."""
    for renderer in list(_OPEN):
        renderer.close()
