"""The env side of a viewer: copy the state out after a step, apply the user's requests before one.

:class:`ViewerSession` runs in the env's thread and touches the simulation only to read
it: after a step it copies ``qpos`` (and mocap poses) of every env, the viewed env's
reward terms, success and camera images into the latest-state slot, at most
:data:`PUBLISH_HZ` times a second (the other steps publish nothing). The viewer draws on
its own thread from its own ``MjData``. So the recorded data is the same with or without a
viewer; only the user's own requests (pause, single step, speed, reset) hold the loop.
"""

from __future__ import annotations

import atexit
import time
from typing import Any, Callable, Optional

import numpy as np

from embodichain_viewer.state import Controls, LatestSlot, Snapshot, image_rgb

#: Most snapshots published per second of wall time while the loop runs.
PUBLISH_HZ = 30.0


class ViewerSession:
    """Attached to a built env by :func:`open_session`.

    Args:
        env: the :class:`~embodichain_core.envs.embodied_env.EmbodiedEnv`.
        viewer: a started viewer with ``controls``, ``slot``, ``alive()`` and ``close()``.
    """

    def __init__(self, env: Any, viewer: Any):
        self.env = env
        self.viewer = viewer
        self.controls: Controls = viewer.controls
        self.slot: LatestSlot = viewer.slot
        self.steps = 0
        self._last_publish = -1.0
        self._last_step = 0.0
        self._closed = False
        #: Further images shown beside the env's cameras (``name -> (H, W, 3)`` uint8), asked for
        #: at each snapshot: ``embodichain dataset view`` shows the recorded frames with it.
        self.extra_images: Optional[Callable[[], dict[str, np.ndarray]]] = None
        # a script that never closes its env (the modular-env tutorial) must not exit mid-frame
        atexit.register(self.close)

    def before_step(self) -> None:
        """Apply a reset request, hold while paused, pace to the chosen speed."""
        c = self.controls
        if c.take_reset():
            env_id = min(max(int(c.env_idx), 0), self.env.num_envs - 1)
            self.env.reset(options={"reset_ids": [env_id], "save_data": False})
        while not c.take_step():  # the user paused the loop
            if not self.viewer.alive():
                c.closed = True
            time.sleep(0.02)
        if c.speed is not None and not c.closed:
            wait = self.env.step_dt / c.speed - (time.monotonic() - self._last_step)
            if wait > 0:
                time.sleep(wait)
        self._last_step = time.monotonic()

    def after_step(self, obs: Any, reward: Any, info: dict) -> None:
        """Publish a snapshot unless one went out less than ``1 / PUBLISH_HZ`` s ago."""
        self.steps += 1
        now = time.monotonic()
        if not self.controls.paused and now - self._last_publish < 1.0 / PUBLISH_HZ:
            return
        self._last_publish = now
        self.slot.put(self.snapshot(obs, reward, info))

    def snapshot(self, obs: Any, reward: Any, info: Optional[dict]) -> Snapshot:
        """Copies of the current state and of the viewed env's readings."""
        sim = self.env.sim
        i = min(max(int(self.controls.env_idx), 0), self.env.num_envs - 1)
        snap = Snapshot(
            step=self.steps,
            qpos=_host(sim.view("qpos")),
            mocap_pos=_host(sim.view("mocap_pos")) if sim.model.nmocap else _empty(self.env.num_envs, 3),
            mocap_quat=_host(sim.view("mocap_quat")) if sim.model.nmocap else _empty(self.env.num_envs, 4),
            env_idx=i,
            episode_step=int(self.env._elapsed_steps[i]),
        )
        if reward is not None:
            snap.reward = float(np.asarray(_host(reward)).reshape(-1)[i])
        info = info or {}
        if "success" in info:
            snap.success = bool(np.asarray(_host(info["success"])).reshape(-1)[i])
        snap.terms = per_env_numbers(info.get("rewards"), i, self.env.num_envs)
        snap.metrics = per_env_numbers(info.get("metrics"), i, self.env.num_envs)
        snap.images = camera_images(obs, i)
        if self.extra_images is not None:
            snap.images.update(self.extra_images())
        return snap

    def close(self) -> None:
        """Stop the viewer (its window or server); idempotent (also run at interpreter exit)."""
        if self.controls.closed and self._closed:
            return
        self._closed = self.controls.closed = True
        atexit.unregister(self.close)
        self.viewer.close()


def per_env_numbers(values: Any, env_idx: int, num_envs: int) -> dict[str, float]:
    """``name -> value of env_idx`` for the entries of ``values`` that hold one number per
    env (or one for all); others (vectors per env, text) are left out."""
    out: dict[str, float] = {}
    for name, value in (values or {}).items() if isinstance(values, dict) else ():
        try:
            arr = np.asarray(_host(value), dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            continue
        if arr.size in (1, num_envs):
            out[str(name)] = float(arr[env_idx if arr.size == num_envs else 0])
    return out


def camera_images(obs: Any, env_idx: int) -> dict[str, np.ndarray]:
    """``"<sensor>/<key>"`` -> ``(H, W, 3)`` uint8 of every image in ``obs["sensor"]``."""
    sensors = obs.get("sensor") if isinstance(obs, dict) else None
    images: dict[str, np.ndarray] = {}
    for uid, data in (sensors or {}).items():
        for key, value in data.items() if isinstance(data, dict) else ():
            if getattr(value, "ndim", 0) >= 3:
                image = image_rgb(value[env_idx])
                if image is not None:
                    images[f"{uid}/{key}"] = image
    return images


def _host(value: Any) -> np.ndarray:
    if hasattr(value, "detach"):
        return value.detach().to("cpu").numpy().copy()
    return np.array(value, copy=True)


def _empty(n: int, width: int) -> np.ndarray:
    return np.zeros((n, 0, width))


def open_session(env: Any, mode: str, port: int = 8080) -> ViewerSession:
    """Start the ``"native"`` or ``"browser"`` viewer of ``env`` and attach it.

    Args:
        env: a built env (``env.sim``, ``env.num_envs``, ``env.step_dt``).
        mode: ``"native"`` (MuJoCo's passive window) or ``"browser"`` (a Viser page).
        port: the first localhost port the browser viewer tries.
    """
    model = env.sim.get_model(0)
    title = f"{type(env).__name__} ({env.num_envs} env(s))"
    if mode == "native":
        from embodichain_viewer.native import NativeViewer

        viewer: Any = NativeViewer(model, env.num_envs, title=title)
    else:
        from embodichain_viewer.browser import BrowserViewer

        viewer = BrowserViewer(model, env.num_envs, port=port, title=title)
        print(f"[embodichain] viewer: {viewer.url}  (over SSH: ssh -L {viewer.port}:localhost:{viewer.port} HOST)")
    session = ViewerSession(env, viewer)
    session.slot.put(session.snapshot(getattr(env, "_init_obs", None), None, None))
    return session
