"""Tests of the {{ cookiecutter.kind }} functor ``{{ cookiecutter.functor_name }}``: its registration, and
an env that uses it by its registered name.

``make_env``, ``check_batched_env``, ``plugin_manager`` and ``register_plugin`` are pytest
fixtures that embodichain-core installs (no conftest.py needed).
"""

from __future__ import annotations

import pytest
{%- if cookiecutter.kind in ("observation", "reward") %}
import torch
{%- endif %}

from embodichain_core.envs import EmbodiedEnvCfg
from embodichain_core.managers import {{ {"observation": "ObservationCfg", "reward": "RewardCfg"}.get(cookiecutter.kind, "EventCfg") }}, SceneEntityCfg
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.shapes import CubeCfg

import {{ cookiecutter.package_name }}.plugin as plugin

NAME = plugin.FUNCTOR_NAME
ARM = """<mujoco><compiler angle="radian"/><worldbody><body name="base">
  <geom type="cylinder" size="0.05 0.02"/>
  <body name="link1" pos="0 0 0.04"><joint name="j1" axis="0 0 1" range="-3 3"/>
    <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
    <body name="link2" pos="0 0 0.2"><joint name="j2" axis="0 1 0" range="-2 2"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.025"/><body name="ee" pos="0.2 0 0"/>
    </body></body></body></worldbody></mujoco>"""
CUBE = SceneEntityCfg(uid="cube")


def scene_cfg(**functors: object) -> EmbodiedEnvCfg:
    """A 2-joint arm and a cube, with the given manager sections (``events={...}``, ...)."""
    return EmbodiedEnvCfg(
        robot=RobotCfg(uid="arm", mjcf=ARM, control_parts={"arm": ["j[1-2]"]}),
        control_parts=["arm"],
        rigid_object=[RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.04, 0.04, 0.04]),
                                     init_pos=(0.4, 0.0, 0.02))],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="lamp", init_pos=(0.0, 0.0, 2.0))]),
        max_episode_steps=20, **functors)


@pytest.fixture
def registered(register_plugin, plugin_manager):
    """The plugin registered into an isolated plugin manager; yields the functor's entry."""
    register_plugin(plugin, name="{{ cookiecutter.distribution_name }}")
    return plugin_manager.registry("functors").entry(NAME)


def test_plugin_registers_the_functor(registered):
    assert registered.provider == "{{ cookiecutter.distribution_name }}"
    assert registered.meta["kind"] == plugin.KIND and registered.meta["category"] == plugin.CATEGORY
    assert callable(registered.resolve())
{% if cookiecutter.kind == "observation" %}

def test_env_uses_the_observation(registered, make_env, check_batched_env):
    cfg = scene_cfg(observations={NAME: ObservationCfg(func=NAME, mode="add", name=f"object/{NAME}",
                                                       params={"entity_cfg": CUBE})})
    env = make_env(cfg, num_envs=2)
    check_batched_env(env)
    obs, _ = env.reset(seed=0)
    assert obs["object"][NAME].shape == (2, 3)
    assert torch.allclose(obs["object"][NAME][:, 0], torch.tensor([0.4, 0.4]), atol=1e-3)
{% elif cookiecutter.kind == "reward" %}

def test_env_uses_the_reward(registered, make_env, check_batched_env):
    cfg = scene_cfg(rewards={NAME: RewardCfg(func=NAME, weight=2.0,
                                             params={"entity_cfg": CUBE, "target": (0.4, 0.0, 0.02)})})
    env = make_env(cfg, num_envs=2)
    check_batched_env(env)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(torch.zeros(2, 2))
    assert info["rewards"][NAME].shape == (2,)
    assert (info["rewards"][NAME] <= 0).all() and (info["rewards"][NAME] > -0.05).all()
    assert torch.allclose(reward, 2.0 * info["rewards"][NAME])
{% elif cookiecutter.kind == "event" %}

def test_env_uses_the_event(registered, make_env, check_batched_env):
    cfg = scene_cfg(events={NAME: EventCfg(func=NAME, mode="reset",
                                           params={"entity_cfg": CUBE, "offset_range": (-0.1, 0.1)})})
    env = make_env(cfg, num_envs=2)
    check_batched_env(env)
    env.reset(seed=0)
    x = env.scene["cube"].get_local_pose()[:, 0]
    assert ((x - 0.4).abs() <= 0.1 + 1e-6).all() and x[0] != x[1]
{% elif cookiecutter.kind == "randomization" %}

def test_env_uses_the_randomization(registered, make_env, check_batched_env):
    cfg = scene_cfg(events={NAME: EventCfg(func=NAME, mode="reset",
                                           params={"entity_cfg": CUBE, "mass_range": (0.2, 0.4)})})
    env = make_env(cfg, num_envs=2)
    check_batched_env(env)
    env.reset(seed=0)
    mass = env.scene["cube"].get_mass()
    assert ((mass >= 0.2 - 1e-6) & (mass <= 0.4 + 1e-6)).all() and mass[0] != mass[1]
{% endif -%}


def test_names_do_not_clash_with_the_installed_plugins():
    """A bare name that another installed plugin registers too becomes ambiguous for users
    (they must then write '{{ cookiecutter.distribution_name }}/<name>'); rename it."""
    from embodichain_core.testing import check_name_clashes

    check_name_clashes(plugin, name="{{ cookiecutter.distribution_name }}")
