"""The browser page and the native window agree: the same readings (success, reward, every
reward term and metric), the same opening camera, and the loop's real speed in the Speed
control (``dataset view --speed 0.25`` shows 0.25x, not max)."""

from __future__ import annotations

import time
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest
from viewer_helpers import free_port

from embodichain_viewer.browser import BrowserViewer, readings_markdown
from embodichain_viewer.native import overlay_text
from embodichain_viewer.session import per_env_numbers
from embodichain_viewer.state import (
    CAMERA_AZIMUTH,
    CAMERA_ELEVATION,
    Controls,
    Snapshot,
    camera_distance,
    camera_pose,
    next_speed,
)

SCENE = """<mujoco><worldbody><light pos="0 0 3"/>
  <geom type="plane" size="3 3 .1"/>
  <body pos="0.8 0.2 0.6"><joint type="hinge"/><geom type="box" size=".1 .1 .3"/></body>
</worldbody></mujoco>"""


def _snapshot() -> Snapshot:
    snap = Snapshot(step=3, qpos=np.zeros((1, 1)), mocap_pos=np.zeros((1, 0, 3)), mocap_quat=np.zeros((1, 0, 4)))
    snap.reward, snap.success = 1.5, True
    snap.terms = {"reach": 0.75, "lift": 0.5}
    snap.metrics = {"fork_height": 0.125}
    return snap


def test_both_viewers_show_every_reward_term_and_metric() -> None:
    snap = _snapshot()
    names, values = overlay_text(snap, Controls())
    page = readings_markdown(snap, dropped=0)
    for name, value in (("success", "yes"), ("reward", "1.5"), ("reach", "0.75"), ("lift", "0.5")):
        assert name in names.splitlines()
        assert value in values.splitlines()
        assert f"| {name} | {value} |" in page
    assert "fork_height" in names.splitlines()
    assert "| fork_height | 0.125 |" in page


def test_metrics_are_read_per_env_and_non_scalars_left_out() -> None:
    import torch

    metrics = {"height": torch.tensor([0.1, 0.2, 0.3]), "shared": 7.0, "pose": torch.zeros(3, 7), "label": "x"}
    assert per_env_numbers(metrics, 1, 3) == pytest.approx({"height": 0.2, "shared": 7.0})
    assert per_env_numbers(None, 0, 3) == {}


def test_the_page_opens_on_the_scene_as_the_window_does() -> None:
    model = mujoco.MjModel.from_xml_string(SCENE)
    position, look_at = camera_pose(model)
    # the native window's camera (MuJoCo's free camera with the same settings)
    cam = mujoco.MjvCamera()
    cam.lookat[:], cam.distance = model.stat.center, camera_distance(model)
    cam.azimuth, cam.elevation = CAMERA_AZIMUTH, CAMERA_ELEVATION
    data, scene = mujoco.MjData(model), mujoco.MjvScene(model, maxgeom=100)
    mujoco.mj_forward(model, data)
    mujoco.mjv_updateScene(model, data, mujoco.MjvOption(), None, cam, mujoco.mjtCatBit.mjCAT_ALL, scene)
    eye = (np.asarray(scene.camera[0].pos) + np.asarray(scene.camera[1].pos)) / 2
    assert np.allclose(position, eye, atol=1e-4)
    assert np.allclose(look_at, model.stat.center)
    assert np.linalg.norm(position - look_at) == pytest.approx(camera_distance(model))
    viewer = BrowserViewer(model, 1, port=free_port())
    try:
        assert viewer.scene.camera_tracking_enabled is False  # world coordinates, like the window
        client = SimpleNamespace(camera=SimpleNamespace(position=None, look_at=None))
        viewer.frame_scene(client)
        assert np.allclose(client.camera.position, position)
        assert np.allclose(client.camera.look_at, look_at)
    finally:
        viewer.close()


@pytest.mark.parametrize(("speed", "label"), [(0.25, "0.25x"), (0.3, "0.3x"), (None, "max")])
def test_the_speed_control_shows_the_loops_speed(speed: float, label: str) -> None:
    model = mujoco.MjModel.from_xml_string(SCENE)
    viewer = BrowserViewer(model, 1, port=free_port())
    try:
        viewer.controls.speed = speed  # what `dataset view --speed` sets
        end = time.monotonic() + 10
        while viewer._speed.value != label and time.monotonic() < end:
            time.sleep(0.05)
        assert viewer._speed.value == label
        assert label in viewer._speed.options
        assert viewer.controls.speed == speed  # showing it changed nothing
    finally:
        viewer.close()


def test_faster_and_slower_step_from_a_speed_between_the_choices() -> None:
    assert next_speed(0.3, 1) == 0.5
    assert next_speed(0.3, -1) == 0.25
    assert next_speed(None, 1) == 0.125
    assert next_speed(4.0, 1) is None  # wraps around to max
    assert next_speed(8.0, -1) == 4.0
