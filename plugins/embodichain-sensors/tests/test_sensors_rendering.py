"""Headless rendering: MUJOCO_GL chosen before MuJoCo is imported (user value first,
then EGL, then OSMesa), a clear error naming what to install, fast vs high quality."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from embodichain_core import rendering
from embodichain_core.sim.cfg import RenderCfg, SimulationManagerCfg
from embodichain_sensors.cfg import CameraCfg

from sensors_helpers import make_scene


def test_user_value_is_respected():
    env = {"MUJOCO_GL": "osmesa"}
    assert rendering.configure_gl(env) == "osmesa"
    assert env == {"MUJOCO_GL": "osmesa"}


@pytest.mark.parametrize(
    "found, want",
    [
        ({"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}, "egl"),
        ({"egl": None, "osmesa": "libOSMesa.so.8"}, "osmesa"),
        ({"egl": None, "osmesa": None}, None),
    ],
)
def test_prefers_egl_then_osmesa(monkeypatch, found, want):
    monkeypatch.setattr(rendering, "find_backend_libraries", lambda: found)
    monkeypatch.setattr(rendering.platform, "system", lambda: "Linux")
    env: dict = {}
    assert rendering.configure_gl(env) == want
    assert env.get("MUJOCO_GL") == want


def test_a_broken_backend_names_what_to_install(monkeypatch):
    class Broken:
        def __init__(self, *args):
            raise OSError("libEGL.so.1: cannot open shared object file")

    monkeypatch.setattr(rendering, "_context_class", lambda backend: Broken)
    with pytest.raises(rendering.RenderingBackendError) as err:
        rendering.create_gl_context(64, 64)
    text = str(err.value)
    assert "MUJOCO_GL=" in text
    assert "cannot open shared object" in text
    assert "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri" in text
    assert "libosmesa6" in text


def test_sim_import_chooses_the_backend_before_mujoco():
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    code = (
        "import sys, os; import embodichain_core.sim; assert 'mujoco' not in sys.modules; "
        "import mujoco.rendering.classic.gl_context as g; print(os.environ.get('MUJOCO_GL'), g._MUJOCO_GL)"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    chosen, seen = out.stdout.split()
    assert chosen == seen
    assert chosen in rendering.HEADLESS_BACKENDS


@pytest.mark.slow
@pytest.mark.parametrize("backend", rendering.HEADLESS_BACKENDS)
def test_each_installed_backend_renders(backend):
    if not rendering.find_backend_libraries()[backend]:
        pytest.skip(f"{backend} is not installed")
    code = (
        "import sys; sys.path.insert(0, %r); from sensors_helpers import make_scene; "
        "from embodichain_sensors.cfg import CameraCfg; "
        "e = CameraCfg.ExtrinsicsCfg(eye=(1, 0, 1), target=(0, 0, 0)); "
        "s, (c,) = make_scene(CameraCfg(uid='c', width=32, height=24, extrinsics=e)); "
        "print(int(c.get_data()['color'][..., :3].float().std() > 1)); c.close()"
    ) % os.path.dirname(__file__)
    env = {**os.environ, "MUJOCO_GL": backend}
    env.pop("PYOPENGL_PLATFORM", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().endswith("1")


@pytest.mark.parametrize("quality", ["fast", "high"])
def test_fast_settings_by_default_high_on_request(quality):
    sim_cfg = SimulationManagerCfg(render_cfg=RenderCfg(quality=quality))
    cfg = CameraCfg(uid="c", width=32, height=24, extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1, 0, 1), target=(0, 0, 0)))
    scene, (cam,) = make_scene(cfg, sim_cfg=sim_cfg)
    try:
        renderer = cam.renderer
        import mujoco

        flags = renderer.scene.flags
        high = quality == "high"
        assert bool(flags[mujoco.mjtRndFlag.mjRND_SHADOW]) is high
        assert bool(flags[mujoco.mjtRndFlag.mjRND_REFLECTION]) is high
        assert (renderer.context.offSamples > 0) is high
        assert scene.model.vis.quality.offsamples == 4  # the model itself is untouched
    finally:
        cam.close()
