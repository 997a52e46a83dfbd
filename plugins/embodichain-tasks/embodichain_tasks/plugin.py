"""Registrations of the embodichain-tasks plugin.

Entry points are lazy ``"module:Class"`` strings: loading the plugin imports no
task module (nor torch or mujoco); ``gym.make(task_id)`` imports it. Each task also
registers its JSON gym config (``config=``), which ``embodichain run-env <id>`` uses.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from embodichain_core.plugins import hookimpl

#: Directory of the JSON gym configs shipped with the package.
CONFIG_DIR = Path(__file__).resolve().parent / "configs"


@dataclass(frozen=True)
class TaskSpec:
    """One task registration: gym id, entry point, episode limit, config file, description."""

    task_id: str
    entry_point: str
    max_episode_steps: int
    config: str
    description: str

    @property
    def config_path(self) -> Path:
        """Absolute path of the task's JSON gym config."""
        return CONFIG_DIR / self.config


#: Every task of this plugin, in the order ``embodichain list tasks`` shows them.
TASKS: tuple[TaskSpec, ...] = (
    TaskSpec(
        "ModularEnv-v1",
        "embodichain_tasks.tutorials.modular_env:ModularEnv",
        100,
        "modular_env.json",
        "The seed tutorial: DexforceW1, stereo head camera, table, fork, drawer, four events",
    ),
    TaskSpec(
        "PushCube-v1",
        "embodichain_tasks.rl.push_cube:PushCubeEnv",
        100,
        "push_cube.json",
        "RL: a 7-DoF arm pushes a cube to a random goal (delta joint actions, shaped reward)",
    ),
    TaskSpec(
        "OpenDrawer-v1",
        "embodichain_tasks.il.open_drawer:OpenDrawerEnv",
        300,
        "open_drawer.json",
        "IL: the W1 pulls the drawer open by its handle (scripted IK demo)",
    ),
    TaskSpec(
        "PickFork-v1",
        "embodichain_tasks.il.pick_fork:PickForkEnv",
        300,
        "pick_fork.json",
        "IL: the W1 picks the fork from the table and lifts it (scripted IK demo)",
    ),
)


@hookimpl
def embodichain_register_tasks(register) -> None:  # noqa: ANN001 - typed by the hookspec
    """Register every task of :data:`TASKS` with its JSON gym config."""
    for task in TASKS:
        register(
            task.task_id,
            task.entry_point,
            max_episode_steps=task.max_episode_steps,
            config=str(task.config_path),
            description=task.description,
        )
