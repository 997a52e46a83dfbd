"""``render_threads``: envs rendered on several OpenGL contexts and threads give the same
images as one context; errors of a job surface; the config is checked."""

from __future__ import annotations

import threading

import pytest
import torch

from sensors_helpers import CUBE_POS

from embodichain_core.config.errors import ConfigError
from embodichain_sensors import camera as camera_module
from embodichain_sensors.cfg import CameraCfg, StereoCameraCfg
from embodichain_sensors import render_pool
from embodichain_sensors.render_pool import RenderPool, render_thread_count

EYE = (CUBE_POS[0] - 0.4, CUBE_POS[1], 0.9)


def stereo(**kw) -> StereoCameraCfg:
    base = dict(
        uid="stereo",
        width=48,
        height=32,
        intrinsics=(40.0, 40.0, 24.0, 16.0),
        left_to_right_pos=(0.06, 0.0, 0.0),
        enable_depth=True,
        enable_mask=True,
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes"),
    )
    base.update(kw)
    return StereoCameraCfg(**base)


def test_threads_render_the_same_images_as_one_context(scene_factory):
    scene, (cam,) = scene_factory(stereo(), robot=True, num_envs=3)
    scene["arm"].set_qpos(torch.tensor([[0.0], [0.6], [-0.6]]), target=False)  # three views of the scene
    cam.cfg.render_threads = 1
    cam.update()
    serial = {k: v.clone() for k, v in cam.get_data().items()}
    assert not torch.equal(serial["color"][0], serial["color"][1])  # the envs differ
    cam.cfg.render_threads = 2
    cam.update()
    pooled = cam.get_data()
    assert cam._pool is not None
    assert cam._pool.threads == 2
    assert serial.keys() == pooled.keys()
    for key in serial:
        assert torch.equal(serial[key], pooled[key]), key
    cam.cfg.render_threads = 1  # the serial renderer still works beside the pool
    cam.update()
    assert torch.equal(cam.get_data()["color_right"], serial["color_right"])


def test_threads_are_capped_at_the_env_count_and_follow_the_config(scene_factory):
    _, (cam,) = scene_factory(stereo(render_threads=4), robot=True, num_envs=3)
    cam.update()
    assert cam._pool is not None
    assert cam._pool.threads == 3
    first = cam.get_data()["color"].clone()
    cam.cfg.render_threads = 2
    cam.update()
    assert cam._pool.threads == 2
    assert torch.equal(cam.get_data()["color"], first)


def test_a_failing_job_is_raised_after_every_job_stopped(scene_factory):
    _, (cam,) = scene_factory(stereo(), robot=True, num_envs=1)
    pool = RenderPool(cam._new_renderer, threads=2)
    done: list[int] = []
    lock = threading.Lock()

    def render(renderer, i):
        if i == 1:
            raise ValueError("env 1 failed")
        with lock:
            done.append(i)

    try:
        with pytest.raises(ValueError, match="env 1 failed"):
            pool.run(4, prepare=lambda r, i: None, render=render)
        assert sorted(done) == [0, 2]  # env 3 waits for renderer 1, whose job failed
        pool.run(2, prepare=lambda r, i: None, render=lambda r, i: done.append(10 + i))
        assert sorted(done)[-2:] == [10, 11]
    finally:
        pool.close()
    with pytest.raises(RuntimeError, match="closed"):
        pool.run(1, prepare=lambda r, i: None, render=lambda r, i: None)


@pytest.mark.parametrize("bad", [0, -1, True, 1.5, "aut", "2"])
def test_render_threads_must_be_a_positive_int_or_auto(bad):
    with pytest.raises(ConfigError, match="render_threads"):
        CameraCfg(uid="cam", render_threads=bad)
    with pytest.raises(ConfigError, match="render_threads.*'auto'"):
        CameraCfg.from_dict({"uid": "cam", "render_threads": "aut"})


@pytest.mark.parametrize("cores, num_envs, threads", [(2, 2, 1), (1, 4, 1), (4, 2, 2), (16, 8, 8), (8, 16, 7)])
def test_auto_render_threads_leave_one_core_and_never_exceed_the_envs(monkeypatch, cores, num_envs, threads):
    monkeypatch.setattr(render_pool.os, "sched_getaffinity", lambda pid: set(range(cores)), raising=False)
    assert CameraCfg.from_dict({"uid": "cam", "render_threads": "auto"}).render_threads == "auto"
    assert render_thread_count("auto", num_envs) == threads
    assert render_thread_count(3, num_envs) == min(3, num_envs)


def test_auto_on_a_backend_that_cannot_hand_contexts_over_is_one_thread_without_a_warning(
    scene_factory, monkeypatch, recwarn
):
    _, (cam,) = scene_factory(stereo(render_threads="auto"), robot=True, num_envs=2)
    monkeypatch.setattr(camera_module, "gl_backend", lambda: "glfw")
    cam.bind()
    assert not [w for w in recwarn if "render_threads" in str(w.message)]
    monkeypatch.setattr(camera_module, "RenderPool", _NoPool)
    cam.update()
    assert cam.get_data()["color"].shape == (2, 32, 48, 4)


def test_a_backend_that_cannot_hand_contexts_over_renders_on_one_thread(scene_factory, monkeypatch):
    _, (cam,) = scene_factory(stereo(render_threads=2), robot=True, num_envs=2)
    monkeypatch.setattr(camera_module, "gl_backend", lambda: "glfw")
    with pytest.warns(UserWarning, match="render_threads = 2: rendering on one thread.*egl or osmesa"):
        cam.bind()
    monkeypatch.setattr(camera_module, "RenderPool", _NoPool)
    cam.update()  # on the camera's own renderer
    assert cam.get_data()["color"].shape == (2, 32, 48, 4)


class _NoPool:
    def __init__(self, *args, **kwargs):
        raise AssertionError("a render pool was built")
