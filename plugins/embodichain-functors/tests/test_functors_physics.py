"""Physics randomization: values land in the chosen envs' model fields only, within
range, reproducibly; bad params are rejected naming the functor and the param."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import apply, event, field, others

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import SceneEntityCfg as E

import embodichain_functors.randomization as rand

IDS = [1, 3]


def test_rigid_object_mass_absolute_lands_in_chosen_envs(build) -> None:
    env = build(events=event(rand.randomize_rigid_object_mass, entity_cfg=E(uid="cube"), mass_range=[2.0, 3.0]))
    body = env.scene["cube"].body_id
    mass0, inertia0 = field(env, "body_mass")[:, body], field(env, "body_inertia")[:, body]
    ids = apply(env, IDS)
    mass, inertia = field(env, "body_mass")[:, body], field(env, "body_inertia")[:, body]
    assert ((mass[ids] >= 2.0) & (mass[ids] <= 3.0)).all()
    assert mass[1] != mass[3]
    assert torch.equal(mass[others(IDS)], mass0[others(IDS)])
    # inertia scales with the mass (same density distribution)
    assert torch.allclose(inertia[ids] / inertia0[ids], (mass[ids] / mass0[ids])[:, None])
    assert torch.allclose(env.scene["cube"].get_mass()[ids].double(), mass[ids], atol=1e-6)


def test_rigid_object_mass_relative_adds_to_configured(build) -> None:
    env = build(
        events=event(rand.randomize_rigid_object_mass, entity_cfg=E(uid="cube"), mass_range=[0.5, 0.6], relative=True)
    )
    body = env.scene["cube"].body_id
    base = float(env.scene.model.body_mass[body])
    apply(env, IDS)
    apply(env, IDS)  # relative to the configured mass: no drift
    mass = field(env, "body_mass")[:, body]
    assert ((mass[IDS] >= base + 0.5) & (mass[IDS] <= base + 0.6)).all()


def test_mass_is_reproducible_from_the_seed(build) -> None:
    cfg = dict(events=event(rand.randomize_rigid_object_mass, entity_cfg=E(uid="cube"), mass_range=[1.0, 5.0]))
    a, b, c = build(**cfg), build(**cfg), build(seed=1, **cfg)
    for env in (a, b, c):
        apply(env, [0, 1, 2, 3])
    body = a.scene["cube"].body_id
    ma, mb, mc = (field(e, "body_mass")[:, body] for e in (a, b, c))
    assert torch.equal(ma, mb)
    assert not torch.equal(ma, mc)
    assert len(set(ma.tolist())) == 4  # every env draws its own value


def test_mass_of_a_group_sets_every_member(build) -> None:
    from embodichain_core.sim.cfg import RigidObjectCfg, RigidObjectGroupCfg
    from embodichain_core.sim.shapes import CubeCfg

    group = RigidObjectGroupCfg(
        uid="blocks",
        rigid_objects={
            "a": RigidObjectCfg(shape=CubeCfg(size=[0.04] * 3), init_pos=(0.3, -0.3, 0.02)),
            "b": RigidObjectCfg(shape=CubeCfg(size=[0.04] * 3), init_pos=(0.3, -0.4, 0.02)),
        },
    )
    env = build(
        rigid_object_group=[group],
        events=event(rand.randomize_rigid_object_mass, entity_cfg=E(uid="blocks"), mass_range=[3.0, 4.0]),
    )
    apply(env, [2])
    for member in env.scene["blocks"].members:
        mass = member.get_mass()
        assert 3.0 <= float(mass[2]) <= 4.0
        assert float(mass[0]) == pytest.approx(1.0)


def test_center_of_mass_offset(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_object_center_of_mass,
            entity_cfg=E(uid="cube"),
            com_pos_offset_range=[[-0.01, -0.02, 0.0], [0.01, 0.02, 0.0]],
        )
    )
    cube = env.scene["cube"]
    ids = apply(env, IDS)
    com = cube.get_com()
    assert (com[ids, 0].abs() <= 0.01 + 1e-6).all()
    assert (com[ids, 1].abs() <= 0.02 + 1e-6).all()
    assert (com[ids, :2].abs() > 0).all()
    assert torch.equal(com[others(IDS)], torch.zeros(2, 3))
    env.step(torch.zeros(env.action_space.shape))  # the simulation accepts the new inertial frame


def test_center_of_mass_skips_kinematic_with_warning(build) -> None:
    env = build(
        events=event(
            rand.randomize_rigid_object_center_of_mass,
            entity_cfg=E(uid="table"),
            com_pos_offset_range=[[0, 0, 0], [0.01, 0.01, 0]],
        )
    )
    with pytest.warns(RuntimeWarning, match="not dynamic"):
        apply(env, IDS)


def test_articulation_mass_per_link_and_dict_ranges(build) -> None:
    env = build(
        events=event(
            rand.randomize_articulation_mass,
            entity_cfg=E(uid="arm"),
            mass_range={"link[1-2]": [2.0, 2.5], "hand": [0.1, 0.2]},
        )
    )
    arm = env.scene["arm"]
    before = arm.get_mass()
    ids = apply(env, IDS)
    after = arm.get_mass()
    names = arm.link_names
    for k, name in enumerate(names):
        if name in ("link1", "link2"):
            assert ((after[ids, k] >= 2.0) & (after[ids, k] <= 2.5)).all()
        elif name == "hand":
            assert ((after[ids, k] >= 0.1) & (after[ids, k] <= 0.2)).all()
        else:
            assert torch.equal(after[:, k], before[:, k])
    assert torch.equal(after[others(IDS)], before[others(IDS)])
    assert after[1, names.index("link1")] != after[1, names.index("link2")]  # per link draws


def test_articulation_mass_regex_selection(build) -> None:
    env = build(
        events=event(
            rand.randomize_articulation_mass, entity_cfg=E(uid="arm"), mass_range=[0.3, 0.4], link_names=["finger_.*"]
        )
    )
    arm = env.scene["arm"]
    apply(env, IDS)
    fingers = [arm.link_names.index(n) for n in ("finger_l", "finger_r")]
    assert ((arm.get_mass()[IDS][:, fingers] >= 0.3) & (arm.get_mass()[IDS][:, fingers] <= 0.4)).all()


def test_friction(build) -> None:
    env = build(events=event(rand.randomize_rigid_object_friction, entity_cfg=E(uid="cube"), friction_range=[0.9, 1.1]))
    before = env.scene["cube"].get_friction()
    ids = apply(env, IDS)
    after = env.scene["cube"].get_friction()
    assert ((after[ids] >= 0.9) & (after[ids] <= 1.1)).all()
    assert torch.equal(after[others(IDS)], before[others(IDS)])


def test_joint_damping_and_stiffness_on_selected_joints(build) -> None:
    events = {
        **event(
            rand.randomize_joint_damping, entity_cfg=E(uid="arm", joint_names=["joint[1-3]"]), damping_range=[1.0, 2.0]
        ),
        "stiff": event(
            rand.randomize_joint_stiffness, entity_cfg=E(uid="arm", joint_names=["joint7"]), stiffness_range=[5.0, 6.0]
        )["ev"],
    }
    env = build(events=events)
    arm = env.scene["arm"]
    ids = apply(env, IDS)
    damping = field(env, "dof_damping")[:, arm.dof_adr]
    assert ((damping[ids][:, :3] >= 1.0) & (damping[ids][:, :3] <= 2.0)).all()
    assert (damping[ids][:, 3:] == 0).all()
    assert (damping[others(IDS)] == 0).all()
    stiffness = field(env, "jnt_stiffness")
    joint7 = int(env.scene.model.dof_jntid[int(arm.dof_adr[6])])
    assert ((stiffness[ids, joint7] >= 5.0) & (stiffness[ids, joint7] <= 6.0)).all()
    assert (stiffness[others(IDS), joint7] == 0).all()


def test_joint_drive_gains(build) -> None:
    env = build(
        events=event(
            rand.randomize_joint_drive,
            entity_cfg=E(uid="arm", joint_names=["joint1"]),
            stiffness_range=[100.0, 200.0],
            damping_range=[10.0, 20.0],
        )
    )
    arm = env.scene["arm"]
    gain = lambda act: field(env, "actuator_gainprm")[:, int(act), 0]  # noqa: E731
    kp0 = gain(arm.pos_act[0])
    ids = apply(env, IDS)
    kp, kv = gain(arm.pos_act[0]), gain(arm.vel_act[0])
    assert ((kp[ids] >= 100) & (kp[ids] <= 200)).all()
    assert ((kv[ids] >= 10) & (kv[ids] <= 20)).all()
    assert torch.equal(kp[others(IDS)], kp0[others(IDS)])
    assert torch.equal(gain(arm.pos_act[1]), torch.full((4,), float(kp0[0]), dtype=gain(arm.pos_act[1]).dtype))


@pytest.mark.parametrize(
    "func, params, param",
    [
        (rand.randomize_rigid_object_mass, {"entity_cfg": E(uid="cube"), "mass_range": [3.0, 1.0]}, "mass_range"),
        (rand.randomize_rigid_object_mass, {"entity_cfg": E(uid="cube"), "mass_range": [-1.0, 1.0]}, "mass_range"),
        (rand.randomize_rigid_object_mass, {"entity_cfg": E(uid="arm"), "mass_range": [1.0, 2.0]}, "entity_cfg"),
        (
            rand.randomize_articulation_mass,
            {"entity_cfg": E(uid="arm"), "mass_range": {"nolink": [1, 2]}},
            "mass_range",
        ),
        (rand.randomize_articulation_mass, {"entity_cfg": E(uid="cube"), "mass_range": [1, 2]}, "entity_cfg"),
        (
            rand.randomize_rigid_object_friction,
            {"entity_cfg": E(uid="cube"), "friction_range": [-1, 1]},
            "friction_range",
        ),
        (rand.randomize_joint_damping, {"entity_cfg": E(uid="arm"), "damping_range": [0, 1, 2]}, "damping_range"),
        (rand.randomize_joint_drive, {"entity_cfg": E(uid="arm")}, "stiffness_range"),
        (
            rand.randomize_rigid_object_center_of_mass,
            {"entity_cfg": E(uid="cube"), "com_pos_offset_range": [[0, 0], [1, 1]]},
            "com_pos_offset_range",
        ),
    ],
)
def test_bad_params_name_functor_and_param(build, func, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        env = build(events=event(func, **params))
        apply(env, IDS)
    assert param in str(err.value)
    assert func.__name__ in str(err.value)
    assert str(err.value).startswith("env.events.ev")
