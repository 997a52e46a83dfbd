"""ModularEnv-v1: the seed tutorial runs as written and its events visibly act."""

from __future__ import annotations

import ast
import difflib
import importlib.util
from pathlib import Path
from typing import Any

import gymnasium as gym
import pytest
import torch

from tasks_helpers import PLUGIN, REPO, normalized_cfg, run_cli, small_stereo

from embodichain_core.config.loader import load_gym_config
from embodichain_tasks.plugin import CONFIG_DIR
from embodichain_tasks.tutorials.modular_env import ExampleCfg

SCRIPT = PLUGIN / "embodichain_tasks" / "tutorials" / "modular_env.py"
SEED = PLUGIN / "tests" / "data" / "seed_modular_env.py"
#: The one non-import change: the seed's endless loop, bounded by ``--max_episodes``.
LOOP_CHANGE = (
    ["    while True:"],
    ["    for _ in episode_loop(args):  # the seed's `while True:`, bounded by --max_episodes"],
)


def _import_lines(source: str) -> set[int]:
    """0-based indices of the lines that belong to import statements."""
    lines: set[int] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            lines.update(range(node.lineno - 1, node.end_lineno))
    return lines


def test_script_differs_from_the_seed_only_in_import_lines() -> None:
    seed, ours = SEED.read_text(), SCRIPT.read_text()
    a, b = seed.splitlines(), ours.splitlines()
    imports_a, imports_b = _import_lines(seed), _import_lines(ours)
    others = []
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if tag == "equal":
            continue
        old = [i for i in range(i1, i2) if i not in imports_a]
        new = [j for j in range(j1, j2) if j not in imports_b]
        if old or new:
            others.append(([a[i] for i in old], [b[j] for j in new]))
    assert others == [LOOP_CHANGE]
    assert "embodichain." not in ours.replace("embodichain_", "")


def _cfg(num_envs: int, small: bool = True) -> Any:
    cfg = ExampleCfg()
    cfg.num_envs, cfg.seed, cfg.verbose = num_envs, 0, False
    return small_stereo(cfg) if small else cfg


def test_one_episode_in_process_events_act() -> None:
    """The tutorial's loop (zero actions, 100 steps) at 96x54: the light moves exactly on
    steps 5, 10, ... of the episode, the fork mesh is redrawn at each reset."""
    env = gym.make("ModularEnv-v1", cfg=_cfg(2))
    base = env.unwrapped
    light = base.scene["point"]
    obs, info = env.reset()
    meshes = [list(base.scene.current_mesh["fork"])]
    previous = light.get_position().clone()
    for step in range(1, 100):
        obs, reward, terminated, truncated, info = env.step(torch.zeros(env.action_space.shape, dtype=torch.float32))
        position = light.get_position().clone()
        moved = (position - previous).norm(dim=-1) > 1e-9
        assert moved.tolist() == [step % 5 == 0] * 2, f"step {step}: light moved {moved.tolist()}"
        previous = position
    assert obs["fork_pose"].shape == (2, 4, 4)
    assert obs["sensor"]["eye_in_head"]["color"].shape[:3] == (2, 54, 96)
    obs, _, _, truncated, _ = env.step(torch.zeros(env.action_space.shape))
    assert truncated.all(), "the registered limit (100 steps) ends the episode"
    for _ in range(3):
        env.reset()
        meshes.append(list(base.scene.current_mesh["fork"]))
    drawn = {m for ms in meshes for m in ms}
    assert len(drawn) >= 3
    assert all(Path(m).parent.name == "fork" for m in drawn)
    assert any(meshes[k][i] != meshes[k + 1][i] for k in range(3) for i in range(2))
    env.close()


def test_fork_mass_is_randomized_on_reset() -> None:
    env = gym.make("ModularEnv-v1", cfg=_cfg(3))
    fork = env.unwrapped.scene["fork"]
    masses = []
    for _ in range(2):
        env.reset()
        masses.append(fork.get_mass().clone())
    assert all(((m >= 0.1 - 1e-6) & (m <= 2.0 + 1e-6)).all() for m in masses)
    assert not torch.allclose(masses[0], masses[1])
    env.close()


@pytest.mark.parametrize("num_envs", [1, 3])
def test_gym_make_with_the_tutorial_cfg(num_envs: int, check_batched_env: Any) -> None:
    """Full resolution, as the tutorial builds it."""
    env = gym.make("ModularEnv-v1", cfg=_cfg(num_envs, small=False))
    assert env.unwrapped.num_envs == num_envs
    check_batched_env(env, steps=2)
    left = env.unwrapped.get_obs()["sensor"]["eye_in_head"]
    assert left["color"].shape[:3] == (num_envs, 540, 960)
    assert {"depth", "mask", "color_right"} <= set(left)
    env.close()


def test_json_config_is_equivalent_to_the_tutorial_cfg() -> None:
    task_id, cfg, extras = load_gym_config(str(CONFIG_DIR / "modular_env.json"))
    assert task_id == "ModularEnv-v1"
    assert cfg.max_episode_steps == 100
    assert normalized_cfg(cfg) == normalized_cfg(ExampleCfg())


@pytest.mark.parametrize("num_envs", [1, 3])
def test_builds_from_the_json_config(num_envs: int, check_batched_env: Any) -> None:
    _, cfg, _ = load_gym_config(str(CONFIG_DIR / "modular_env.json"), {"num_envs": num_envs, "verbose": False})
    env = gym.make("ModularEnv-v1", cfg=small_stereo(cfg))
    assert env.unwrapped.num_envs == num_envs
    check_batched_env(env, steps=2)
    env.close()


def test_run_env_few_steps(embodichain_cli: Any) -> None:
    out = embodichain_cli("run-env", "ModularEnv-v1", "--max_episodes", "1", "--num_envs", "1", "--max_steps", "5")
    assert "run-env summary: ModularEnv-v1" in out.stdout
    assert "episodes     1 (1 env(s))" in out.stdout


@pytest.mark.slow
def test_run_env_one_episode(embodichain_cli: Any) -> None:
    out = embodichain_cli("run-env", "ModularEnv-v1", "--max_episodes", "1", "--num_envs", "1")
    assert "episodes     1 (1 env(s))" in out.stdout
    assert "env steps    100" in out.stdout


@pytest.mark.slow
def test_tutorial_script_runs_two_episodes_headless() -> None:
    """The script itself, as documented (960x540 stereo, two envs, two episodes)."""
    out = run_cli(
        [
            _python(),
            "-m",
            "embodichain_tasks.tutorials.modular_env",
            "--headless",
            "--num_envs",
            "2",
            "--max_episodes",
            "2",
        ],
        timeout=600,
    )
    assert "Environment initialized: ModularEnv" in out.stdout


def test_docs_page_is_generated_from_the_script() -> None:
    spec = importlib.util.spec_from_file_location("gen_tutorial_docs", PLUGIN / "scripts" / "gen_tutorial_docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    page = (REPO / "docs" / "tutorial_modular_env.md").read_text()
    assert page == module.render(), "run plugins/embodichain-tasks/scripts/gen_tutorial_docs.py"
    assert SCRIPT.read_text().rstrip() in page


def _python() -> str:
    import sys

    return sys.executable
