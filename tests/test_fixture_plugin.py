"""The fixture plugin under tests/fixture_plugins, discovered through a real
``embodichain`` entry point: its task, functor, robot and data root must be discoverable
from a plain ``import embodichain_core``.

The plugin is test-only: the set-up never installs it (no ``FixtureReach-v0`` in a user's
``embodichain list tasks``). The ``fixture_plugins`` fixture of ``tests/conftest.py``
exposes it to this module, as an installation would (a ``*.dist-info`` with its entry
point on ``sys.path`` and ``PYTHONPATH``).
"""

import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest
import torch

from embodichain_core.plugins import get_registry
from embodichain_core.sim.cfg import RobotCfg
from embodichain_core.testing.env_checks import check_batched_env, make_env_instance

pytestmark = pytest.mark.usefixtures("fixture_plugins")


def test_the_fixture_plugin_is_not_installed_for_users(fixture_plugins_site: Path) -> None:
    """Without the test's exposure a fresh interpreter knows no fixture plugin."""
    path = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p and p != str(fixture_plugins_site)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(path)}
    code = (
        "import importlib.metadata as md, embodichain_core, gymnasium as gym\n"
        "dists = [d.metadata['Name'] for d in md.distributions()]\n"
        "print('embodichain-fixture' in dists, 'FixtureReach-v0' in gym.registry)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env, check=False
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "False"], (
        "the test-only plugin embodichain-fixture is installed in this environment (an older "
        "scripts/setup_env.sh installed it): run scripts/setup_env.sh again or "
        "pip uninstall embodichain-fixture"
    )


def test_task_id_registered_on_import_without_importing_the_task_module():
    code = (
        "import sys, embodichain_core, gymnasium as gym\n"
        "assert 'FixtureReach-v0' in gym.registry, 'task id not registered'\n"
        "assert 'embodichain_fixture.tasks' not in sys.modules, 'task module imported eagerly'\n"
        "assert 'torch' not in sys.modules and 'mujoco' not in sys.modules, 'import is not cheap'\n"
        "env = gym.make('FixtureReach-v0', num_envs=2, verbose=False)\n"
        "assert 'embodichain_fixture.tasks' in sys.modules\n"
        "print(env.unwrapped.num_envs)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().endswith("2")


def test_gym_make_runs_the_plugin_task():
    env = make_env_instance("FixtureReach-v0", num_envs=3)
    assert env.max_episode_steps == 15  # the registered limit, kept inside the env
    assert not isinstance(gym.make("FixtureReach-v0", verbose=False), gym.wrappers.TimeLimit)
    check_batched_env(env)
    obs, _ = env.reset(seed=1)
    assert obs["object"]["cube_pos"].shape == (3, 3)
    # the reset event resolved "fixture_nudge_cube" from the registry: cube x varies per env
    assert len(set(obs["object"]["cube_pos"][:, 0].tolist())) == 3


def test_make_vec_uses_the_batched_env():
    env = gym.make_vec("FixtureReach-v0", num_envs=2, vectorization_mode="vector_entry_point", verbose=False)
    direct = gym.make("FixtureReach-v0", num_envs=2, verbose=False)
    action = torch.tensor([[0.1, -0.2, 0.3], [-0.3, 0.2, 0.0]])
    try:
        assert env.num_envs == 2
        first, _ = env.reset(seed=0)
        want_first, _ = direct.reset(seed=0)
        obs, reward, terminated, truncated, info = env.step(action)
        want_obs, want_reward, *_ = direct.step(action)
        assert reward.shape == (2,)
        # the same values as the batched env made directly, per env
        assert torch.equal(first["object"]["cube_pos"], want_first["object"]["cube_pos"])
        assert torch.equal(obs["object"]["cube_pos"], want_obs["object"]["cube_pos"])
        assert torch.equal(reward, want_reward)
        assert first["object"]["cube_pos"][0, 0] != first["object"]["cube_pos"][1, 0]  # rows are the envs'
    finally:
        env.close()
        direct.close()


def test_episode_limit_truncates_every_env():
    env = gym.make("FixtureReach-v0", num_envs=2, verbose=False).unwrapped
    env.reset(seed=0)
    for _ in range(14):
        _, _, _, truncated, _ = env.step(torch.zeros(2, 3))
        assert not truncated.any()
    _, _, _, truncated, info = env.step(torch.zeros(2, 3))
    assert truncated.all()
    assert info["_final_obs"].all()
    assert (env.elapsed_steps == 0).all()


def test_plugin_robot_and_data_root_resolve():
    cfg = RobotCfg.from_dict({"class_type": "FixtureArm", "init_pos": [0, 0, 0.1]})
    assert type(cfg).__name__ == "FixtureArmCfg"
    assert cfg.init_pos == (0, 0, 0.1)
    assert "fixture_nudge_cube" in get_registry("functors")
    from embodichain_core.sim.data import get_data_path

    assert get_data_path("tetra.obj").endswith("tetra.obj")
