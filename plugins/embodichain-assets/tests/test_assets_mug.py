"""The mug: its non-convex handle is hulled by default, decomposed by coacd on request (cached)."""

from __future__ import annotations

import pytest

from embodichain_assets import catalog
from embodichain_core.sim.scene_build import convex
from embodichain_core.sim.cfg import RigidObjectCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import MeshCfg


@pytest.fixture
def coacd_calls(monkeypatch, tmp_path):
    """Counts coacd runs; the coacd cache goes to an empty temporary folder."""
    monkeypatch.setenv("EMBODICHAIN_CACHE_DIR", str(tmp_path))
    calls = []
    real = convex._run_coacd
    monkeypatch.setattr(convex, "_run_coacd", lambda *a, **k: calls.append(1) or real(*a, **k))
    return calls


def _mug_scene(max_hulls: int) -> Scene:
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    shape = MeshCfg(fpath=catalog.MUG, max_convex_hull_num=max_hulls)
    scene.add_rigid_object(RigidObjectCfg(uid="mug", shape=shape, init_pos=(0.0, 0.0, 0.002)))
    scene.build()
    return scene


def test_default_mug_needs_no_decomposition(coacd_calls):
    scene = _mug_scene(max_hulls=1)
    assert coacd_calls == []
    assert len(scene["mug"].geom_ids) == 2  # body + the handle's hull
    scene.sim.step(100)
    assert float(scene["mug"].get_local_pose()[0, 2]) == pytest.approx(0.0, abs=5e-3)  # stands on its foot


@pytest.mark.slow
def test_decomposed_handle_is_cached_between_builds(coacd_calls):
    first = _mug_scene(max_hulls=8)
    assert len(coacd_calls) == 1  # only the handle goes through coacd; the body is convex
    hulls = len(first["mug"].geom_ids)
    assert 3 <= hulls <= 1 + 8
    second = _mug_scene(max_hulls=8)
    assert len(coacd_calls) == 1  # the second build reads the cache
    assert len(second["mug"].geom_ids) == hulls
