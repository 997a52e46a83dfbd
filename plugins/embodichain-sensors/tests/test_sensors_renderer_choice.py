"""A camera renderer that cannot batch the backend's envs is one ``ConfigError`` when the env
validates its config, before the scene is built: it names the camera's ``renderer`` key and the
renderer that works. CUDA is simulated (``torch.cuda`` reports one GPU) the way the core's
test of ``--device cuda`` does; nothing reaches Warp, since the error comes first."""

from __future__ import annotations

from typing import Any

import pytest
import torch

from sensors_helpers import HEAD_ARM

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.sim.cfg import RenderCfg, RobotCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_sensors.cfg import CameraCfg
from embodichain_sensors.renderer_choice import choose_renderer

OPENGL_ON_GPU = "renderer 'opengl' cannot batch camera 'cam' on sim_cfg.backend 'warp' with sim_device 'cuda'"


def _sim(**kw: Any) -> SimulationManagerCfg:
    return SimulationManagerCfg(**{"backend": "warp", "sim_device": "cuda", **kw})


def _env_cfg(sim_cfg: SimulationManagerCfg, **camera: Any) -> EmbodiedEnvCfg:
    cam = CameraCfg(uid="cam", width=32, height=24, intrinsics=(30.0, 30.0, 16.0, 12.0), **camera)
    return EmbodiedEnvCfg(
        num_envs=2,
        verbose=False,
        robot=RobotCfg(uid="arm", mjcf=HEAD_ARM, control_parts={"all": ["j1"]}),
        sim_cfg=sim_cfg,
        sensor=[cam],
    )


@pytest.fixture
def one_gpu(monkeypatch: pytest.MonkeyPatch) -> None:
    """``torch.cuda`` reports one GPU, and building a scene fails the test. The env's step
    counters, made before its config check, are then made in host memory (no GPU here)."""
    zeros = torch.zeros

    def host_zeros(*args: Any, device: Any = None, **kw: Any) -> torch.Tensor:
        return zeros(*args, device=None if str(device).startswith("cuda") else device, **kw)

    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 1)
    monkeypatch.setattr(torch, "zeros", host_zeros)
    monkeypatch.setattr(Scene, "build", lambda *a, **k: pytest.fail("the scene was built"))


@pytest.mark.parametrize("device", ["cuda", "cuda:0"])
def test_the_rule_refuses_opengl_on_a_gpu_and_names_the_warp_renderer(device: str) -> None:
    with pytest.raises(ConfigError, match="renderer 'opengl' cannot batch") as err:
        choose_renderer(_sim(sim_device=device), "opengl", "cam", "sensor[0]")
    assert err.value.path == "sensor[0].renderer"
    assert f"with sim_device {device!r}" in err.value.reason
    assert "use renderer 'warp'" in err.value.reason
    assert choose_renderer(_sim(sim_device=device), None, "cam", "sensor[0]") == "warp"  # the default batches
    assert choose_renderer(_sim(sim_device="cpu"), "opengl", "cam", "sensor[0]") == "opengl"  # host memory there
    assert choose_renderer(SimulationManagerCfg(), "opengl", "cam", "sensor[0]") == "opengl"


def test_opengl_on_a_gpu_fails_before_the_scene_is_built(one_gpu: None) -> None:
    cfg = _env_cfg(_sim(), renderer="opengl")
    with pytest.raises(ConfigError, match=OPENGL_ON_GPU) as err:
        EmbodiedEnv(cfg)
    assert err.value.path == "sensor[0].renderer"
    assert "use renderer 'warp'" in str(err.value)
    with pytest.raises(ConfigError, match=OPENGL_ON_GPU):
        cfg.validate(memory=False)  # the same check from the config alone


def test_what_the_warp_renderer_cannot_do_fails_before_the_scene_is_built(one_gpu: None) -> None:
    """Renderer 'warp' on backend mujoco_batch, and quality 'high' with it: both were errors when
    the camera bound to the compiled scene; now the config check raises them."""
    with pytest.raises(ConfigError, match="renderer 'warp' renders the worlds of sim_cfg.backend 'warp'") as err:
        EmbodiedEnv(_env_cfg(SimulationManagerCfg(), renderer="warp"))
    assert err.value.path == "sensor[0].renderer"
    assert "use renderer 'opengl'" in err.value.reason
    with pytest.raises(ConfigError, match="no reflections or MSAA; use quality 'fast'") as err:
        EmbodiedEnv(_env_cfg(_sim(render_cfg=RenderCfg(quality="high"))))
    assert err.value.path == "sim_cfg.render_cfg.quality"
    assert "renderer 'opengl' on this camera, which needs sim_cfg.sim_device 'cpu'" in err.value.reason
    with pytest.raises(ConfigError, match="use quality 'fast', or renderer: 'opengl' on this camera$"):
        cfg = _env_cfg(_sim(sim_device="cpu", render_cfg=RenderCfg(quality="high")))
        cfg.validate(memory=False)
