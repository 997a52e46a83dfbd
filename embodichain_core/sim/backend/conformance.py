"""Conformance checks of the simulation interface, for any backend.

A backend author runs :func:`check_backend` with a factory of their backend::

    from embodichain_core.sim.backend.conformance import check_backend
    check_backend(lambda model, num_envs: MyBackend(model, num_envs))

Each check builds a fresh backend of :data:`SCENE` (a falling free box, a hinge with a
position actuator, a light; MuJoCo's own autoreset disabled, as in every scene the core
builds, so that a divergence stays visible) and raises ``AssertionError`` naming what broke: persistent
views, stepping every env and a subset (the others untouched, a subset step equal to a
full one on a deterministic backend), reset, lazy forward, model field writes and reads
(as arrays and as device tensors) with their derived constants, and divergence reported by
both kinds of step.
"""

from __future__ import annotations

from typing import Callable, Mapping

import mujoco
import numpy as np
import torch

from embodichain_core.sim.backend.interface import DERIVED_FIELDS, STATE_FIELDS, SimBackend

SCENE = """
<mujoco>
  <option timestep="0.002"><flag autoreset="disable"/></option>
  <worldbody>
    <light name="lamp" pos="0 0 2"/>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="box" pos="0 0 0.5"><freejoint/><geom name="box" type="box" size="0.05 0.05 0.05"/></body>
    <body name="arm" pos="1 0 0.1"><joint name="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/></body>
  </worldbody>
  <actuator><position name="drive" joint="hinge" kp="20" dampratio="1"/></actuator>
</mujoco>
"""
NUM_ENVS = 3
Factory = Callable[[mujoco.MjModel, int], SimBackend]


def _make(factory: Factory) -> tuple[SimBackend, mujoco.MjModel, int]:
    model = mujoco.MjModel.from_xml_string(SCENE)
    sim = factory(model, NUM_ENVS)
    assert isinstance(sim, SimBackend), f"{type(sim).__name__} does not implement SimBackend"
    return sim, model, model.body("box").id


def _np(t: torch.Tensor) -> np.ndarray:
    return t.detach().cpu().double().numpy().copy()


def _arrays(sim: SimBackend) -> Mapping[str, np.ndarray]:
    """``sim.arrays`` (an attribute only backends with ``capabilities.host_arrays`` have)."""
    return getattr(sim, "arrays")  # noqa: B009


def check_views(factory: Factory) -> None:
    """Views: shapes, dtype, device, and the same tensors through step, reset, forward, writes."""
    sim, model, box = _make(factory)
    views = {name: sim.view(name) for name in STATE_FIELDS + ("xpos", "xquat", "qfrc_actuator", "sensordata")}
    assert views["qpos"].shape == (NUM_ENVS, model.nq), views["qpos"].shape
    assert views["xpos"].shape == (NUM_ENVS, model.nbody, 3), views["xpos"].shape
    assert views["qpos"].dtype == sim.dtype
    assert views["qpos"].device == sim.device
    attribute = getattr(sim, "qpos")  # noqa: B009 (sim.qpos: named views are not protocol members)
    assert attribute is views["qpos"], "sim.qpos and sim.view('qpos') differ"
    assert sim.tensors["qpos"] is views["qpos"], "sim.tensors and sim.view('qpos') differ"
    arrays = dict(_arrays(sim)) if sim.capabilities.host_arrays else {}
    assert sim.capabilities.host_arrays or not hasattr(sim, "arrays"), "host arrays without host_arrays"
    sim.step(2)
    sim.step(1, env_ids=[1])
    sim.reset([0])
    sim.declare_per_env(["geom_friction"])
    sim.set_model_field("body_mass", [2], box, 3.0)
    sim.forward()
    for name, view in views.items():
        assert sim.view(name) is view, f"the view of {name!r} was replaced"
    for name, array in arrays.items():
        assert _arrays(sim)[name] is array, f"the numpy view of {name!r} was replaced"
    assert set(DERIVED_FIELDS) >= {"xpos", "xquat", "qfrc_actuator", "sensordata"}


def check_step(factory: Factory) -> None:
    """Every env falls; a subset step moves only its envs; a deterministic backend's subset
    steps give what a full step gives."""
    sim, model, box = _make(factory)
    start = _np(sim.view("qpos"))
    assert sim.step(5) == [], "a step of a healthy scene reported divergence"
    after_full = _np(sim.view("qpos"))
    z = model.jnt_qposadr[model.body_jntadr[box]] + 2
    assert (after_full[:, z] < start[:, z]).all(), "the free box did not fall in every env"
    sim.reset()
    assert sim.step(5, env_ids=[1]) == []
    moved = _np(sim.view("qpos"))
    assert (moved[[0, 2]] == start[[0, 2]]).all(), "a subset step changed other envs"
    assert moved[1, z] < start[1, z], "a subset step did not step its env"
    if sim.capabilities.deterministic:
        sim.step(5, env_ids=[0, 2])
        assert (_np(sim.view("qpos")) == after_full).all(), "subset steps differ from a full step"


def check_reset_and_forward(factory: Factory) -> None:
    """Reset restores model defaults of its envs only; writes + mark_dirty reach derived views."""
    sim, model, box = _make(factory)
    sim.step(10)
    stepped = _np(sim.view("qpos"))
    sim.reset([0])
    assert np.allclose(_np(sim.view("qpos"))[0], model.qpos0), "reset did not restore the model defaults"
    assert (_np(sim.view("qpos"))[1:] == stepped[1:]).all(), "reset changed other envs"
    adr = model.jnt_qposadr[model.body_jntadr[box]]
    sim.view("qpos")[2, adr : adr + 3] = torch.tensor([0.3, -0.2, 0.7], dtype=sim.dtype)
    sim.mark_dirty([2])
    assert np.allclose(_np(sim.view("xpos"))[2, box], [0.3, -0.2, 0.7]), "a marked write did not reach xpos"
    sim.view("qpos")[1, adr] = 0.9
    sim.forward([1])
    assert np.isclose(_np(sim.view("xpos"))[1, box, 0], 0.9), "forward(env_ids) did not update xpos"
    data = sim.get_data(2)
    assert np.allclose(data.qpos, _np(sim.view("qpos"))[2]), "get_data(i) is not env i's state"


def check_model_fields(factory: Factory) -> None:
    """Per-env writes read back, leave other envs alone and update derived constants."""
    sim, model, box = _make(factory)
    geom = model.geom("box").id
    sim.declare_per_env(["geom_friction"])
    assert sim.is_per_env("geom_friction"), "declare_per_env did not make the field per env"
    sim.set_model_field("body_mass", [1], box, 2.5)
    sim.set_model_field("geom_friction", [0, 2], (geom, 0), np.array([0.3, 0.9]))
    mass = np.array(sim.model_field("body_mass")[:, box])
    rtol = 0.0 if sim.dtype == torch.float64 else 1e-6  # a float32 backend rounds what it stores
    assert np.allclose(mass, [model.body_mass[box], 2.5, model.body_mass[box]], rtol=rtol, atol=0), mass
    friction = np.array(sim.model_field("geom_friction")[:, geom, 0])
    assert np.allclose(friction, [0.3, model.geom_friction[geom, 0], 0.9], rtol=rtol, atol=0), friction
    assert sim.is_per_env("body_mass")
    sim.step(1)
    assert np.isclose(sim.get_model(1).body_subtreemass[box], 2.5), "derived constants did not follow the mass"
    sim.set_body_masses([0], [box], np.array([[4.0]]))
    assert np.isclose(
        sim.model_field("body_inertia")[0, box, 0], model.body_inertia[box, 0] * 4.0 / model.body_mass[box]
    ), "set_body_masses did not scale the inertia"
    _check_model_tensors(sim, ("body_mass", "geom_friction", "body_pos"))


def _check_model_tensors(sim: SimBackend, names: tuple) -> None:
    """``model_tensor`` holds ``model_field``'s values, on the sim's device, per-env or shared."""
    for name in names:
        tensor, values = sim.model_tensor(name), sim.model_field(name)
        assert tensor.device == torch.device(sim.device), f"model_tensor({name!r}) is on {tensor.device}"
        assert tuple(tensor.shape) == values.shape, f"model_tensor({name!r}) has shape {tuple(tensor.shape)}"
        assert np.array_equal(tensor.detach().cpu().numpy(), values), f"model_tensor({name!r}) differs from model_field"


def check_divergence(factory: Factory) -> None:
    """Both kinds of step report a non-finite env; a subset step's report repeats at the next
    full step (even after the state was made finite by writes), and a reset drops it."""
    sim, model, _ = _make(factory)
    sim.view("qvel")[2, 0] = float("nan")
    sim.mark_dirty([2])
    assert sim.step(1) == [2], "a full step did not report the non-finite env"
    sim.reset([2])
    for reset in (False, True):
        sim.view("qvel")[1, 0] = float("nan")
        sim.mark_dirty([1])
        assert sim.step(1, env_ids=[0, 1]) == [1], "a subset step did not report the non-finite env"
        if reset:
            sim.reset([1])
            assert sim.step(1) == [], "a reset env's old divergence was reported"
            continue
        sim.view("qpos")[1] = torch.as_tensor(model.qpos0, dtype=sim.dtype)
        sim.view("qvel")[1] = 0.0
        sim.mark_dirty([1])
        assert sim.step(1) == [1], "the subset step's divergence was not reported at the next full step"
        assert sim.step(1) == [], "a reported divergence was reported twice"


CHECKS = (check_views, check_step, check_reset_and_forward, check_model_fields, check_divergence)


def check_backend(factory: Factory) -> None:
    """Run every check of this module on backends made by ``factory(model, num_envs)``."""
    for check in CHECKS:
        check(factory)
