"""The browser viewer: a Viser page on a localhost port, drawn by mjviser.

Viser (a maintained web 3-D viewer with a GUI toolkit) serves the page; mjviser turns a
MuJoCo model into a Viser scene and brings the env selector, the camera controls and the
overlay toggles (contact points and forces, body and joint frames). This module adds the
run controls (pause, single step, reset, speed), the task readings and the camera images.
The server listens on 127.0.0.1 only; from another machine, forward the port over SSH.
"""

from __future__ import annotations

import threading
from typing import Any, Optional

import mujoco
import numpy as np
import viser

from embodichain_viewer.state import (
    SPEEDS,
    Controls,
    LatestSlot,
    Snapshot,
    camera_distance,
    camera_pose,
    reading_rows,
    speed_label,
)


class BrowserViewer:
    """Serves the page and draws the newest snapshot on its own thread.

    Args:
        model: the env's ``MjModel`` (a copy is drawn; the env's is never touched).
        num_envs: envs in each snapshot (the selector's range).
        port: first port tried; a port in use moves on to the next free one.
        title: shown above the readings.
    """

    def __init__(self, model: mujoco.MjModel, num_envs: int, port: int = 8080, title: str = ""):
        from mjviser import ViserMujocoScene

        self.controls = Controls()
        self.slot = LatestSlot()
        self.model = model
        self.num_envs = int(num_envs)
        self._data = mujoco.MjData(model)
        self.server = viser.ViserServer(host="127.0.0.1", port=int(port), verbose=False)
        self.port = int(self.server.get_port())
        self.url = f"http://localhost:{self.port}"
        self.scene = ViserMujocoScene(self.server, model, num_envs=self.num_envs)
        self.scene.show_only_selected = True
        # world coordinates (no body re-centred), so the page opens on the scene as the window does
        self.scene.camera_tracking_enabled = False
        self.frames = 0  # snapshots drawn
        self.last: Optional[Snapshot] = None
        self._images: dict[str, Any] = {}
        self._stop = threading.Event()
        self._build_gui(title)
        self._thread = threading.Thread(target=self._loop, name="embodichain-browser-viewer", daemon=True)
        self._thread.start()

    # -- gui ------------------------------------------------------------------------------------
    def _build_gui(self, title: str) -> None:
        gui = self.server.gui
        tabs = gui.add_tab_group()
        with tabs.add_tab("Run", icon=viser.Icon.PLAYER_PLAY):
            gui.add_markdown(f"**{title}**" if title else "")
            paused = gui.add_checkbox("Paused", initial_value=False, hint="Hold the env loop before its next step")
            step = gui.add_button("Single step", hint="Run one control step, then hold")
            reset = gui.add_button("Reset env", hint="Reset the selected env (its episode is not recorded)")
            self._speeds = {speed_label(s): s for s in SPEEDS}
            speed = gui.add_dropdown(
                "Speed",
                tuple(self._speeds),
                initial_value=speed_label(self.controls.speed),
                hint="Multiple of real time",
            )
            self._speed = speed
            self._status = gui.add_markdown("waiting for the first step")
        with tabs.add_tab("Scene", icon=viser.Icon.VIDEO):  # env selector, camera
            self.scene.create_scene_gui(camera_distance=camera_distance(self.model))
        with tabs.add_tab("Visualization", icon=viser.Icon.EYE):  # contacts, frames, ...
            self.scene.create_overlay_gui()
        self._cameras_tab = tabs.add_tab("Cameras", icon=viser.Icon.CAMERA)
        with self._cameras_tab:
            self._no_images = gui.add_markdown("no camera sensor in this env")

        @paused.on_update
        def _(_: Any) -> None:
            self.controls.paused = bool(paused.value)

        @step.on_click
        def _(_: Any) -> None:
            self.controls.request_step()
            paused.value = True  # type: ignore[misc]  # viser sets it (its stub types the property read-only)

        @reset.on_click
        def _(_: Any) -> None:
            self.controls.reset = True

        @speed.on_update
        def _(_: Any) -> None:
            self.controls.speed = self._speeds.get(str(speed.value), self.controls.speed)

        self.server.on_client_connect(self.frame_scene)

    def frame_scene(self, client: Any) -> None:
        """Point a newly connected page's camera at the scene as the native window opens
        (:func:`~embodichain_viewer.state.camera_pose`)."""
        position, look_at = camera_pose(self.model)
        client.camera.position = tuple(position)
        client.camera.look_at = tuple(look_at)

    def show_speed(self) -> None:
        """Show the loop's speed in the Speed control when it was set elsewhere
        (``dataset view --speed``), adding a choice for a speed the list lacks."""
        label = speed_label(self.controls.speed)
        if self._speed.value == label:
            return
        if label not in self._speeds:
            self._speeds[label] = self.controls.speed
            self._speed.options = tuple(self._speeds)
        self._speed.value = label  # type: ignore[misc]  # viser sets it (its stub types the property read-only)

    # -- drawing --------------------------------------------------------------------------------
    def _loop(self) -> None:
        seen, selected = 0, int(self.scene.env_idx)
        while not self._stop.is_set():
            if int(self.scene.env_idx) != selected:  # the page's env selector moved
                selected = self.controls.env_idx = int(self.scene.env_idx)
            seen, snap = self.slot.get(seen, timeout=0.1)
            self.show_speed()
            if snap is not None:
                self.draw(snap)

    def draw(self, snap: Snapshot) -> None:
        """Pose every env's bodies from ``snap`` and refresh the readings and images."""
        sel = min(int(self.scene.env_idx), self.num_envs - 1)
        # with the others hidden (the default) only the selected env's kinematics are computed
        xpos, xmat = body_poses(self.model, self._data, snap, only=sel if self.scene.show_only_selected else None)
        self.scene.update_from_arrays(
            xpos,
            xmat,
            mocap_pos=snap.mocap_pos,
            mocap_quat=snap.mocap_quat,
            env_idx=sel,
            qpos=snap.qpos,
            qvel=np.zeros((self.num_envs, self.model.nv)),
        )
        self._status.content = readings_markdown(snap, self.slot.dropped)
        self._show_images(snap.images)
        self.last = snap
        self.frames += 1

    def _show_images(self, images: dict[str, np.ndarray]) -> None:
        for name, image in images.items():
            handle = self._images.get(name)
            if handle is None:
                self._no_images.visible = False
                with self._cameras_tab:
                    handle = self.server.gui.add_image(image, label=name, format="jpeg")
                self._images[name] = handle
            else:
                handle.image = image

    def alive(self) -> bool:
        """The server runs (a page may or may not be open)."""
        return not self._stop.is_set()

    def close(self) -> None:
        """Stop drawing and shut the server down."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.server.stop()


def body_poses(
    model: mujoco.MjModel, data: mujoco.MjData, snap: Snapshot, only: Optional[int] = None
) -> tuple[np.ndarray, np.ndarray]:
    """``(num_envs, nbody, 3)`` positions and ``(num_envs, nbody, 3, 3)`` rotations of ``snap``
    (forward kinematics on the viewer's own ``MjData``); ``only``: compute that env alone and
    give every env its poses (the others are hidden)."""
    n = snap.qpos.shape[0]
    xpos = np.empty((n, model.nbody, 3))
    xmat = np.empty((n, model.nbody, 3, 3))
    for e in range(n) if only is None else (only,):
        data.qpos[:] = snap.qpos[e]
        if model.nmocap:
            data.mocap_pos[:] = snap.mocap_pos[e]
            data.mocap_quat[:] = snap.mocap_quat[e]
        mujoco.mj_kinematics(model, data)
        xpos[e] = data.xpos
        xmat[e] = data.xmat.reshape(-1, 3, 3)
    if only is not None:
        xpos[:], xmat[:] = xpos[only], xmat[only]
    return xpos, xmat


def readings_markdown(snap: Snapshot, dropped: int) -> str:
    """The viewed env's step and readings (:func:`~embodichain_viewer.state.reading_rows`:
    success, reward, reward terms, metrics) as a small Markdown table."""
    lines = [
        f"**env {snap.env_idx}**, episode step {snap.episode_step} (step {snap.step})",
        "",
        "| reading | value |",
        "|---|---|",
        *(f"| {name} | {value} |" for name, value in reading_rows(snap)),
        "",
        f"frames skipped by the viewer: {dropped}",
    ]
    return "\n".join(lines)
