"""Video frames of an env without a colour camera: its scene from MuJoCo's default free
camera, rendered with the camera sensors' offscreen renderer (``embodichain-sensors``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from embodichain_core.config.errors import ConfigError

__all__ = ["SceneFrames"]


def _host(value: Any) -> np.ndarray:
    if hasattr(value, "detach"):
        return value.detach().to("cpu").numpy()
    return np.asarray(value)


class SceneFrames:
    """``frames()`` -> the scene of env 0 as ``(height, width, 3)`` uint8.

    Args:
        env: the (``num_envs=1``) env.
        width, height: the frame size.

    Raises:
        ConfigError: ``env``: ``embodichain-sensors`` (the renderer) is not installed.
    """

    def __init__(self, env: Any, width: int = 320, height: int = 240):
        try:
            from embodichain_sensors.renderer import SensorRenderer
        except ImportError:
            raise ConfigError(
                "env",
                "the env has no colour camera and embodichain-sensors is not installed: lerobot records "
                "a video of the first episodes (env.render()); install it or add a camera to the gym config",
            ) from None
        import mujoco

        self.sim = env.unwrapped.sim
        self.data = mujoco.MjData(self.sim.model)
        self.renderer = SensorRenderer(self.sim.model, width, height)
        mujoco.mjv_defaultFreeCamera(self.sim.model, self.renderer.camera)

    def __call__(self) -> np.ndarray:
        """The current frame (a new array)."""
        import mujoco

        model = self.sim.model
        self.data.qpos[:] = _host(self.sim.view("qpos"))[0]
        if model.nmocap:
            self.data.mocap_pos[:] = _host(self.sim.view("mocap_pos"))[0]
            self.data.mocap_quat[:] = _host(self.sim.view("mocap_quat"))[0]
        mujoco.mj_kinematics(model, self.data)
        with self.renderer.current():
            self.renderer.update_scene(model, self.data)
            rgb, _ = self.renderer.render(color=True)
        if rgb is None:  # render(color=True) always returns the colour image
            raise RuntimeError("the scene renderer returned no colour image")
        return np.array(rgb[::-1], copy=True)

    def close(self) -> None:
        """Free the renderer."""
        self.renderer.close()
