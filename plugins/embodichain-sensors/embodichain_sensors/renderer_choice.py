"""Which renderer a camera uses, and the settings it cannot render, checked from the config.

:func:`choose_renderer` is the one rule, run twice: by ``CameraCfg.check_values`` when the
env validates its config (before the scene is built), and by the camera when it binds (a
scene built without an env). It imports neither MuJoCo nor torch.

The rule (docs/sensors.md, "Renderers"):

* ``renderer`` unset: ``"warp"`` on ``sim_cfg.backend: warp``, else ``"opengl"``;
* ``"warp"`` renders the worlds of backend ``warp`` only, with ``render_cfg.quality: fast``;
* ``"opengl"`` draws one env at a time on the host from host copies of the state: on backend
  ``warp`` with a CUDA ``sim_device`` that is a device-to-host copy per env and frame, so it
  is refused there (``"warp"`` batches every env in one launch on the device).

Example:
    >>> from embodichain_core.sim.cfg import SimulationManagerCfg
    >>> choose_renderer(SimulationManagerCfg(backend="warp"), None, "cam", "sensor[0]")
    'warp'
"""

from __future__ import annotations

from typing import Any, Optional

from embodichain_core.config.errors import ConfigError

#: Camera renderers (``CameraCfg.renderer``).
RENDERERS = ("warp", "opengl")


def on_gpu(sim_cfg: Any) -> bool:
    """Whether ``sim_cfg`` runs backend ``warp`` on a CUDA device (``cuda``, ``cuda:N``)."""
    device = str(getattr(sim_cfg, "sim_device", "cpu") or "cpu").strip().lower()
    return getattr(sim_cfg, "backend", "mujoco_batch") == "warp" and device.startswith("cuda")


def opengl_hint(gpu: bool) -> str:
    """How to get the OpenGL renderer instead of the Warp one, for an error message."""
    if gpu:
        return "renderer 'opengl' on this camera, which needs sim_cfg.sim_device 'cpu' (or backend 'mujoco_batch')"
    return "renderer: 'opengl' on this camera"


def choose_renderer(sim_cfg: Any, renderer: Optional[str], uid: str, path: str) -> str:
    """The renderer of camera ``uid`` (``renderer``, or the backend's default).

    Args:
        sim_cfg: the ``SimulationManagerCfg`` (``backend``, ``sim_device``, ``render_cfg``).
        renderer: the camera's ``renderer`` setting (``None``: the default).
        uid: the camera's uid, for messages.
        path: the camera's config path (``sensor[0]``); errors name ``<path>.renderer``.

    Raises:
        ConfigError: ``"warp"`` on another backend, ``"opengl"`` on backend ``warp`` with a
            CUDA device (both at ``<path>.renderer``), or ``"warp"`` with
            ``render_cfg.quality`` other than ``"fast"`` (at ``sim_cfg.render_cfg.quality``).
    """
    backend = getattr(sim_cfg, "backend", "mujoco_batch")
    chosen = renderer or ("warp" if backend == "warp" else "opengl")
    if chosen == "warp" and backend != "warp":
        raise ConfigError(
            f"{path}.renderer",
            f"renderer 'warp' renders the worlds of sim_cfg.backend 'warp', not backend {backend!r}; "
            "use renderer 'opengl' (or leave it unset)",
        )
    gpu = on_gpu(sim_cfg)
    if chosen == "opengl" and gpu:
        raise ConfigError(
            f"{path}.renderer",
            f"renderer 'opengl' cannot batch camera {uid!r} on sim_cfg.backend 'warp' with sim_device "
            f"{sim_cfg.sim_device!r}: it draws one env at a time on the host from a copy of the device "
            "state; use renderer 'warp' (every env in one launch on the device; the default there), "
            "or sim_device 'cpu' for OpenGL images",
        )
    quality = getattr(getattr(sim_cfg, "render_cfg", None), "quality", "fast")
    if chosen == "warp" and quality != "fast":
        raise ConfigError(
            "sim_cfg.render_cfg.quality",
            f"{quality!r}: MuJoCo Warp's renderer (camera {uid!r}, backend 'warp') has no reflections "
            f"or MSAA; use quality 'fast', or {opengl_hint(gpu)}",
        )
    return chosen
