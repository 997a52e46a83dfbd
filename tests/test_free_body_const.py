"""The closed form of free bodies' inertial constants matches a full mj_setConst."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from embodichain_core.sim.backend.batch_sim import BatchSim
from embodichain_core.sim.backend.free_body_const import eligible_bodies

SCENE = """
<mujoco>
  <asset>
    <mesh name="wedge" vertex="0 0 0  0.08 0 0  0 0.05 0  0 0 0.03  0.08 0.05 0.01  0.02 0.01 0.06"/>
  </asset>
  <worldbody>
    <light name="lamp" pos="0 0 2" mode="{light_mode}"/>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="arm" pos="0 0 0.1">
      <joint name="hinge" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
    </body>
    <body name="box" pos="0.5 0 0.1">
      <freejoint/>
      <geom type="box" size="0.05 0.04 0.03"/>
      <geom type="sphere" size="0.02" pos="0.05 0 0"/>
      <geom type="capsule" size="0.01 0.03" pos="0 0.05 0" euler="40 0 10"/>
      <geom type="ellipsoid" size="0.02 0.01 0.015" pos="-0.04 -0.02 0.01" euler="0 30 60"/>
      <site name="mark" pos="0.01 0 0"/>
    </body>
    <body name="wedge" pos="-0.3 0.4 0.2">
      <freejoint/>
      <geom type="mesh" mesh="wedge"/>
      <geom type="mesh" mesh="wedge" pos="0.03 0.02 0.05" euler="90 0 20"/>
    </body>
    <body name="tilted" pos="0.2 -0.4 0.3" euler="0 0 45">
      <freejoint/>
      <geom name="tilted_box" type="box" size="0.04 0.03 0.02" pos="0.1 0 0" euler="0 0 30"/>
      <site name="at_com" pos="0.1 0 0" euler="0 0 30"/>
    </body>
    <body name="ball" pos="-0.5 0 0.2" quat="0.9 0.1 0.3 0.2">
      <freejoint name="ball_free"/>
      <geom type="sphere" size="0.05"/>
    </body>
    <body name="chain" pos="0 0.5 0.2">
      <freejoint/>
      <geom type="box" size="0.03 0.03 0.03"/>
      <body name="tail" pos="0.1 0 0">
        <joint axis="0 1 0"/>
        <geom type="box" size="0.02 0.02 0.02"/>
      </body>
    </body>
    <body name="table" mocap="true" pos="1 1 0">
      <geom type="box" size="0.2 0.2 0.2"/>
    </body>
  </worldbody>
  <actuator><position joint="hinge" kp="10" dampratio="1"/></actuator>
</mujoco>
"""

DERIVED = (
    "body_invweight0",
    "body_subtreemass",
    "body_sameframe",
    "dof_M0",
    "dof_invweight0",
    "dof_length",
    "bvh_aabb",
    "geom_sameframe",
    "site_sameframe",
    "actuator_acc0",
    "tendon_invweight0",
)


def _spec(light_mode: str = "fixed", xml: str = SCENE) -> mujoco.MjSpec:
    spec = mujoco.MjSpec.from_string(xml.format(light_mode=light_mode))
    for body in spec.bodies:
        body.simple = False  # centres of mass move
    return spec


def _sims(light_mode: str = "fixed", xml: str = SCENE) -> tuple[BatchSim, BatchSim, mujoco.MjModel]:
    spec = _spec(light_mode, xml)
    model = spec.compile()
    fast = BatchSim(model, 6, nthread=1)
    full = BatchSim(model, 6, nthread=1)
    full.constants.fast = False  # always the full mj_setConst
    return fast, full, model


def _write(
    sims: tuple[BatchSim, ...],
    model: mujoco.MjModel,
    name: str,
    env_ids: list[int],
    rng: np.random.Generator,
    rotate: bool = True,
):
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
    mass = rng.uniform(0.1, 3.0, len(env_ids))
    inertia = rng.uniform(1e-4, 1e-2, (len(env_ids), 3))
    com = rng.uniform(-0.02, 0.02, (len(env_ids), 3))
    quat = rng.normal(size=(len(env_ids), 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    for sim in sims:
        sim.set_model_field("body_mass", env_ids, body, mass)
        sim.set_model_field("body_inertia", env_ids, body, inertia)
        sim.set_model_field("body_ipos", env_ids, body, com)
        if rotate:
            sim.set_model_field("body_iquat", env_ids, body, quat)


def _full_set_const_calls(sim: BatchSim, monkeypatch) -> list:
    """The ids of every whole-model ``set_const`` of ``sim`` from now on."""
    calls: list = []
    original = sim.batch.set_const
    monkeypatch.setattr(sim.batch, "set_const", lambda ids=None: (calls.append(ids), original(ids))[1])
    return calls


def _derived(sim: BatchSim) -> dict[str, np.ndarray]:
    return {name: np.array(sim.model_field(name)) for name in DERIVED}


def test_only_free_leaf_bodies_without_actuators_are_eligible():
    model = _spec().compile()
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in eligible_bodies(model)]
    assert names == ["box", "wedge", "tilted", "ball"]
    assert eligible_bodies(_spec("trackcom").compile()) == []  # a light follows the scene's centre of mass


def test_fast_path_matches_full_set_const(monkeypatch):
    fast, full, model = _sims()
    calls = _full_set_const_calls(fast, monkeypatch)
    rng = np.random.default_rng(0)
    for round_ in range(3):
        _write((fast, full), model, "box", [0, 2, 3], rng)
        _write((fast, full), model, "ball", [1, 2, 5] if round_ else [0, 1, 2, 3, 4, 5], rng)
        fast.flush_const()
        full.flush_const()
        got, want = _derived(fast), _derived(full)
        for name in DERIVED:
            np.testing.assert_allclose(got[name], want[name], rtol=1e-12, atol=1e-14, err_msg=name)
    box = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box")
    for sim in (fast, full):  # masses only: the frame-dependent constants are kept
        sim.set_body_masses([0, 4], [box], np.array([[0.7], [2.5]]))
        sim.flush_const()
    _assert_same(fast, full)
    assert calls == []  # the whole model's mj_setConst never ran
    for sim in (fast, full):  # the objects fall onto the floor: contacts use the constants
        sim.step(60)
    np.testing.assert_allclose(fast.qpos.numpy(), full.qpos.numpy(), rtol=0, atol=1e-9)


def test_other_writes_take_the_full_path(monkeypatch):
    fast, full, model = _sims()
    calls = _full_set_const_calls(fast, monkeypatch)
    rng = np.random.default_rng(1)
    _write((fast, full), model, "chain", [0, 1], rng)  # has a child body
    _write((fast, full), model, "box", [2], rng)
    fast.flush_const()
    full.flush_const()
    assert len(calls) == 1
    assert list(calls[0]) == [0, 1]
    got, want = _derived(fast), _derived(full)
    for name in DERIVED:
        np.testing.assert_allclose(got[name], want[name], rtol=1e-12, atol=1e-14, err_msg=name)


@pytest.mark.parametrize("field,index", [("geom_size", 0), ("body_mass", "arm")])
def test_non_inertial_or_robot_fields_are_not_fast(field, index):
    fast, _, model = _sims()
    if index == "arm":
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "arm")
    assert not fast.constants.closed_form_field(field, index)
    assert fast.constants.closed_form_field("body_ipos", (mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box"),))


def _assert_same(fast: BatchSim, full: BatchSim) -> None:
    got, want = _derived(fast), _derived(full)
    for name in DERIVED:
        np.testing.assert_allclose(got[name], want[name], rtol=1e-12, atol=1e-14, err_msg=name)


def test_a_com_moved_off_a_geom_frame_keeps_the_geom_in_place(monkeypatch):
    """The tilted box's geom frame is its inertial frame (``sameframe`` INERTIA): moving
    the centre of mass must re-classify it, or the geom would follow the centre of mass."""
    fast, full, model = _sims()
    calls = _full_set_const_calls(fast, monkeypatch)
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "tilted")
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "tilted_box")
    assert model.geom_sameframe[geom] == mujoco.mjtSameFrame.mjSAMEFRAME_INERTIA
    for sim in (fast, full):
        sim.set_model_field("body_ipos", [1, 3], body, np.zeros((2, 3)))
        sim.set_model_field("body_mass", [4], body, 2.0)
        sim.flush_const()
        sim.forward(None)
    assert calls == []
    _assert_same(fast, full)
    for sim in (fast, full):
        same = mujoco.mjtSameFrame
        assert list(np.asarray(sim.model_field("geom_sameframe"))[[0, 1, 3], geom]) == [
            int(same.mjSAMEFRAME_INERTIA),
            int(same.mjSAMEFRAME_INERTIAROT),
            int(same.mjSAMEFRAME_INERTIAROT),
        ]
    geom_xpos = fast.get_data(1).geom_xpos[geom]
    np.testing.assert_allclose(geom_xpos, fast.get_data(0).geom_xpos[geom], atol=1e-12)


def test_collision_filters_and_inertia_of_a_swapped_part_skip_mj_set_const(monkeypatch):
    """What a per-env mesh swap writes: geom collision filters (of any body) and a free
    body's inertia; the bodies' aggregate filters follow without mj_setConst."""
    fast, full, model = _sims()
    calls = _full_set_const_calls(fast, monkeypatch)
    rng = np.random.default_rng(4)
    box, arm = (mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("box", "arm"))
    box_geoms = list(range(model.body_geomadr[box], model.body_geomadr[box] + model.body_geomnum[box]))
    for sim in (fast, full):
        sim.set_model_field("geom_contype", [0, 3], box_geoms, np.array([[0, 1, 4, 0], [2, 0, 0, 8]]))
        sim.set_model_field("geom_conaffinity", [3], box_geoms[1], 5)
        sim.set_model_field("geom_contype", [5], int(model.body_geomadr[arm]), 6)  # a robot link's geom
    _write((fast, full), model, "box", [0, 3], rng)
    for sim in (fast, full):
        sim.flush_const()
    assert calls == []
    _assert_same(fast, full)
    for name in ("body_contype", "body_conaffinity"):
        np.testing.assert_array_equal(fast.model_field(name), full.model_field(name), err_msg=name)
    assert fast.model_field("body_contype")[0, box] == 5
    assert fast.model_field("body_contype")[3, box] == 10


def test_a_per_env_armature_takes_the_full_path(monkeypatch):
    fast, full, model = _sims()
    calls = _full_set_const_calls(fast, monkeypatch)
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "ball")
    dofs = list(range(model.body_dofadr[body], model.body_dofadr[body] + 6))
    for sim in (fast, full):
        sim.set_model_field("dof_armature", [2], dofs, np.full((1, 6), 0.01))
        sim.flush_const()
    calls.clear()
    _write((fast, full), model, "ball", [1, 2], np.random.default_rng(3))
    fast.flush_const()
    full.flush_const()
    assert len(calls) == 1  # the closed form assumes no armature
    _assert_same(fast, full)


def test_armature_in_the_model_makes_a_body_ineligible():
    spec = _spec()
    spec.joint("ball_free").armature = 0.02
    model = spec.compile()
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in eligible_bodies(model)]
    assert names == ["box", "wedge", "tilted"]
