"""The embodichain-tasks plugin: lazy registrations with configs, package data, docs."""

from __future__ import annotations

import json
import subprocess
import sys

import gymnasium as gym
import pytest

import embodichain_core  # noqa: F401  (loads the installed plugins)
from embodichain_core.plugins import task_registry

from tasks_helpers import PLUGIN, REPO

from embodichain_tasks import plugin

EXPECTED = {
    "ModularEnv-v1": ("embodichain_tasks.tutorials.modular_env:ModularEnv", 100, "modular_env.json"),
    "PushCube-v1": ("embodichain_tasks.rl.push_cube:PushCubeEnv", 100, "push_cube.json"),
    "OpenDrawer-v1": ("embodichain_tasks.il.open_drawer:OpenDrawerEnv", 300, "open_drawer.json"),
    "PickFork-v1": ("embodichain_tasks.il.pick_fork:PickForkEnv", 300, "pick_fork.json"),
}


@pytest.mark.parametrize("task_id", sorted(EXPECTED))
def test_task_is_registered_with_its_config(task_id: str) -> None:
    entry_point, limit, config = EXPECTED[task_id]
    entry = task_registry().entry(task_id)
    assert entry.provider == "embodichain-tasks"
    assert entry.meta["max_episode_steps"] == limit
    assert entry.meta["config"] == str(PLUGIN / "embodichain_tasks" / "configs" / config)
    assert entry.meta["description"]
    assert gym.registry[task_id].entry_point == entry_point


def test_loading_the_plugin_imports_no_task_module() -> None:
    code = (
        "import sys, embodichain_core, gymnasium as gym; assert 'PushCube-v1' in gym.registry; "
        "print(sorted(m for m in sys.modules if m.startswith('embodichain_tasks')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == "['embodichain_tasks', 'embodichain_tasks.plugin']"


@pytest.mark.parametrize("task_id", ["ModularEnv-v1", "PushCube-v1"])
def test_config_file_names_its_task(task_id: str) -> None:
    data = json.loads((PLUGIN / "embodichain_tasks" / "configs" / EXPECTED[task_id][2]).read_text())
    assert data["id"] == task_id
    assert data["max_episode_steps"] == EXPECTED[task_id][1]


def test_configs_are_package_data() -> None:
    text = (PLUGIN / "pyproject.toml").read_text()
    assert '"configs/*.json"' in text
    assert 'embodichain-tasks = "embodichain_tasks.plugin"' in text
    for dep in (
        "embodichain-core",
        "embodichain-functors",
        "embodichain-robots",
        "embodichain-sensors",
        "embodichain-assets",
    ):
        assert f'"{dep}"' in text


def test_every_task_is_listed_in_the_docs() -> None:
    text = (REPO / "docs" / "tasks.md").read_text()
    for task in plugin.TASKS:
        assert f"`{task.task_id}`" in text
    assert "images/ppo_push_cube.png" in text
