"""The browser viewer: a page on a localhost port, drawing the env's state as it steps,
with the run controls acting on the loop and the camera images and readings beside it."""

from __future__ import annotations

import socket
import urllib.request

import numpy as np
import pytest
from viewer_helpers import action, demo_env, free_port, wait_for

from embodichain_viewer.browser import body_poses
from embodichain_viewer.state import Controls, LatestSlot, Snapshot


@pytest.fixture
def browser_env(every_step_published: None) -> object:
    env = demo_env("browser", free_port())
    yield env
    env.close()


def test_page_is_served_on_loopback_and_follows_the_steps(browser_env: object) -> None:
    env = browser_env.unwrapped  # type: ignore[attr-defined]
    viewer = env._viewer.viewer
    assert viewer.server.get_host() == "127.0.0.1"
    with urllib.request.urlopen(f"http://127.0.0.1:{viewer.port}/", timeout=10) as page:
        assert page.status == 200
        assert b"<html" in page.read().lower()
    env.reset()
    poses = []
    for k in range(2):
        for j in range(5):
            browser_env.step(action(browser_env, 10 * k + j))  # type: ignore[attr-defined]
        wait_for(lambda: viewer.last is not None and viewer.last.step == env._viewer.steps, "the last step drawn")
        np.testing.assert_array_equal(viewer.last.qpos, env.sim.view("qpos").numpy())
        poses.append(body_poses(viewer.model, viewer._data, viewer.last)[0])
    assert not np.allclose(poses[0], poses[1])  # the drawn bodies moved with the env
    assert set(viewer.last.images) == {"cam/color", "cam/depth"}
    assert viewer.last.images["cam/color"].shape == (24, 32, 3)
    assert "**env 0**" in viewer._status.content
    assert "| success |" in viewer._status.content
    assert set(viewer._images) == {"cam/color", "cam/depth"}


def test_a_taken_port_moves_to_the_next_free_one(every_step_published: None) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        env = demo_env("browser", port)
        try:
            assert env.unwrapped._viewer.viewer.port != port
        finally:
            env.close()


def test_reset_and_single_step_act_on_the_loop(browser_env: object) -> None:
    env = browser_env.unwrapped  # type: ignore[attr-defined]
    session = env._viewer
    env.reset()
    for k in range(3):
        browser_env.step(action(browser_env, k))  # type: ignore[attr-defined]
    assert int(env._elapsed_steps[1]) == 3
    session.controls.env_idx = 1
    session.controls.reset = True
    session.controls.request_step()  # paused, one step granted: the step runs, then the loop holds
    browser_env.step(action(browser_env, 3))  # type: ignore[attr-defined]
    assert [int(x) for x in env._elapsed_steps] == [4, 1]  # env 1 was reset before the step
    assert session.controls.paused
    assert not session.controls.take_step()


def test_controls_hold_only_while_paused() -> None:
    c = Controls()
    assert c.take_step()
    c.paused = True
    assert not c.take_step()
    c.request_step()
    assert c.take_step()
    assert not c.take_step()
    c.closed = True  # a closed viewer never holds the loop
    assert c.take_step()


def test_the_slot_keeps_only_the_newest_snapshot() -> None:
    slot = LatestSlot()
    snaps = [
        Snapshot(step=i, qpos=np.zeros((1, 1)), mocap_pos=np.zeros((1, 0, 3)), mocap_quat=np.zeros((1, 0, 4)))
        for i in range(3)
    ]
    for snap in snaps:
        slot.put(snap)
    version, got = slot.get(0, timeout=0.0)
    assert got is snaps[2]
    assert slot.dropped == 2
    assert slot.get(version, timeout=0.0) == (version, None)
