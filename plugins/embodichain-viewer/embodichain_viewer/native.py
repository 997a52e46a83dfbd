"""The native viewer: MuJoCo's own passive window (needs a display).

MuJoCo's viewer brings the 3-D view, its camera, and the overlay toggles of its left panel
(contact points and forces, joint and body frames, ...). This module draws the newest
snapshot on its own ``MjData`` and adds, as overlays, the viewed env's readings (top left)
and its camera images (bottom right), and these keys:

=============  ==================================================
Key            Action
=============  ==================================================
``P``          pause / play the env loop
``N``          one control step (pauses)
``R``          reset the viewed env (its episode is not recorded)
``]`` / ``[``  next / previous env
``=`` / ``-``  faster / slower (``max``, then multiples of real time)
=============  ==================================================

(``P``, ``N``, ``R``, ``[`` and ``]`` are free in MuJoCo's viewer; ``=`` and ``-`` too.)
"""

from __future__ import annotations

import threading
from typing import Any, Optional

import mujoco
import numpy as np

from embodichain_viewer.state import (
    CAMERA_AZIMUTH,
    CAMERA_ELEVATION,
    Controls,
    LatestSlot,
    Snapshot,
    camera_distance,
    next_speed,
    reading_rows,
    speed_label,
)

#: GLFW key codes of the keys above.
KEYS = {"pause": 80, "step": 78, "reset": 82, "next": 93, "prev": 91, "faster": 61, "slower": 45}
HELP = "P pause/play  N step  R reset  [ ] env  - = speed"


class NativeViewer:
    """MuJoCo's passive window, fed by its own thread.

    Args:
        model: the env's ``MjModel`` (the window draws a copy).
        num_envs: envs in each snapshot.
        title: shown in the overlay.
    """

    def __init__(self, model: mujoco.MjModel, num_envs: int, title: str = ""):
        import mujoco.viewer

        self.controls = Controls()
        self.slot = LatestSlot()
        self.model = model
        self.num_envs = int(num_envs)
        self.title = title
        self.data = mujoco.MjData(model)
        self.frames = 0
        self.last: Optional[Snapshot] = None
        self._stop = threading.Event()
        before = set(threading.enumerate())
        self.handle = mujoco.viewer.launch_passive(model, self.data, key_callback=self.on_key)
        # the window's render thread: joined on close, so the process never exits mid-frame
        self._window_threads = [t for t in threading.enumerate() if t not in before]
        with self.handle.lock():  # the whole scene in view, as the browser viewer starts
            self.handle.cam.lookat[:] = model.stat.center
            self.handle.cam.distance = camera_distance(model)
            self.handle.cam.azimuth, self.handle.cam.elevation = CAMERA_AZIMUTH, CAMERA_ELEVATION
        self._thread = threading.Thread(target=self._loop, name="embodichain-native-viewer", daemon=True)
        self._thread.start()

    def on_key(self, key: int) -> None:
        """Apply one of :data:`KEYS` to the controls."""
        c = self.controls
        if key == KEYS["pause"]:
            c.paused = not c.paused
        elif key == KEYS["step"]:
            c.request_step()
        elif key == KEYS["reset"]:
            c.reset = True
        elif key in (KEYS["next"], KEYS["prev"]):
            c.env_idx = (c.env_idx + (1 if key == KEYS["next"] else -1)) % self.num_envs
        elif key in (KEYS["faster"], KEYS["slower"]):
            c.speed = next_speed(c.speed, 1 if key == KEYS["faster"] else -1)

    def _loop(self) -> None:
        seen = 0
        while not self._stop.is_set() and self.handle.is_running():
            seen, snap = self.slot.get(seen, timeout=0.1)
            if snap is not None:
                self.draw(snap)
        self.controls.closed = True

    def draw(self, snap: Snapshot) -> None:
        """Show the viewed env of ``snap`` with its readings and camera images."""
        i = min(snap.env_idx, self.num_envs - 1)
        with self.handle.lock():
            self.data.qpos[:] = snap.qpos[i]
            if self.model.nmocap:
                self.data.mocap_pos[:] = snap.mocap_pos[i]
                self.data.mocap_quat[:] = snap.mocap_quat[i]
            mujoco.mj_forward(self.model, self.data)  # contacts too, for the contact overlay
        self.handle.set_texts([(None, mujoco.mjtGridPos.mjGRID_TOPLEFT, *overlay_text(snap, self.controls))])
        viewport = self.handle.viewport
        right = viewport.left + viewport.width if viewport is not None else 0
        self.handle.set_images(image_viewports(snap.images, right=right))
        self.handle.sync()
        self.last = snap
        self.frames += 1

    def alive(self) -> bool:
        """The window is open."""
        return self.handle.is_running()

    def close(self) -> None:
        """Close the window."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.handle.close()
        for thread in self._window_threads:
            thread.join(timeout=5.0)


def overlay_text(snap: Snapshot, controls: Controls) -> tuple[str, str]:
    """The two columns of the readings overlay."""
    state = "paused" if controls.paused else f"running ({speed_label(controls.speed)})"
    rows = [
        ("env", f"{snap.env_idx} / step {snap.episode_step}"),
        ("loop", state),
        *reading_rows(snap),
        ("keys", HELP),
    ]
    return "\n".join(r[0] for r in rows), "\n".join(r[1] for r in rows)


def image_viewports(images: dict[str, np.ndarray], right: int = 0, height: int = 160) -> list[tuple[Any, np.ndarray]]:
    """Camera images shrunk to at most ``height`` px, side by side along the bottom edge,
    ending at x = ``right`` (the 3-D view's right edge; 0: start at the left edge) and
    together at most half as wide as ``right`` (shrunk further when needed)."""
    if not images:
        return []
    widest = right // 2 if right else None
    step = max(1, int(np.ceil(max(i.shape[0] for i in images.values()) / height)))
    while True:
        smalls = [np.ascontiguousarray(i[::step, ::step]) for i in images.values()]
        width = sum(s.shape[1] + 4 for s in smalls)
        if widest is None or width <= widest or step > 64:
            break
        step += 1
    left = max(0, right - width) if right else 0
    out = []
    for small in smalls:
        out.append((mujoco.MjrRect(left, 0, small.shape[1], small.shape[0]), small))
        left += small.shape[1] + 4
    return out
