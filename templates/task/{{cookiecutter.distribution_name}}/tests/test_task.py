"""Tests of {{ cookiecutter.task_id }}: registration, the batched loop, the JSON config.

``make_env``, ``check_batched_env``, ``plugin_manager`` and ``register_plugin`` are pytest
fixtures that embodichain-core installs (no conftest.py needed).
"""

from __future__ import annotations

import gymnasium as gym
import torch

from embodichain_core.config.loader import load_gym_config

import {{ cookiecutter.package_name }}.plugin as plugin
from {{ cookiecutter.package_name }}.task import {{ cookiecutter.class_name }}Cfg

TASK_ID = plugin.TASK_ID


def test_plugin_registers_the_task_and_the_robot(register_plugin, plugin_manager):
    register_plugin(plugin, name="{{ cookiecutter.distribution_name }}")
    entry = plugin_manager.registry("tasks").entry(TASK_ID)
    assert entry.meta["max_episode_steps"] == plugin.MAX_EPISODE_STEPS
    assert entry.meta["config"] == str(plugin.CONFIG_PATH)
    assert "{{ cookiecutter.class_name }}Arm" in plugin_manager.registry("robots")


def test_gym_make_builds_resets_and_steps_two_envs(make_env, check_batched_env):
    assert TASK_ID in gym.registry, "install the package (pip install -e .) so its entry point is found"
    env = make_env(TASK_ID, num_envs=2)
    assert env.num_envs == 2 and env.max_episode_steps == plugin.MAX_EPISODE_STEPS
    check_batched_env(env)
    obs, info = env.reset(seed=0)
    assert obs["object"]["cube_pos"].shape == (2, 3)
    obs, reward, terminated, truncated, info = env.step(torch.zeros(2, 3))
    assert reward.shape == (2,) and (reward <= 0).all()
    assert info["metrics"]["distance"].shape == (2,)


def test_reset_event_moves_the_cube_per_env(make_env):
    env = make_env(TASK_ID, num_envs=2)
    obs, _ = env.reset(seed=1)
    cube = obs["object"]["cube_pos"]
    assert not torch.equal(cube[0], cube[1])


def test_json_config_builds_the_same_env(make_env, check_batched_env):
    task_id, cfg, extras = load_gym_config(str(plugin.CONFIG_PATH), {"num_envs": 2},
                                           cfg_cls={{ cookiecutter.class_name }}Cfg)
    assert task_id == TASK_ID and extras["max_episodes"] >= 1
    env = make_env(TASK_ID, num_envs=2, cfg=cfg)
    check_batched_env(env)
    reference = make_env(TASK_ID, num_envs=2)
    assert env.single_observation_space == reference.single_observation_space
    assert env.single_action_space == reference.single_action_space


def test_names_do_not_clash_with_the_installed_plugins():
    """A bare name that another installed plugin registers too becomes ambiguous for users
    (they must then write '{{ cookiecutter.distribution_name }}/<name>'); rename it."""
    from embodichain_core.testing import check_name_clashes

    check_name_clashes(plugin, name="{{ cookiecutter.distribution_name }}")
