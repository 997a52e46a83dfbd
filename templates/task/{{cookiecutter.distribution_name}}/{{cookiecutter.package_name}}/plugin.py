"""Registrations of {{ cookiecutter.distribution_name }} (its ``embodichain`` entry point).

Every installed plugin is loaded on ``import embodichain_core``, so this module imports
nothing heavy: it registers lazy ``"module:attr"`` strings, which are imported on first
use (``gymnasium.make("{{ cookiecutter.task_id }}")`` imports the task module).
"""

from __future__ import annotations

from pathlib import Path

from embodichain_core.plugins import RobotRegister, TaskRegister, hookimpl

TASK_ID = "{{ cookiecutter.task_id }}"
MAX_EPISODE_STEPS = {{ cookiecutter.max_episode_steps }}
#: The task's JSON gym config: ``embodichain run-env {{ cookiecutter.task_id }}`` runs it.
CONFIG_PATH = Path(__file__).resolve().parent / "configs" / "gym_config.json"


@hookimpl
def embodichain_register_tasks(register: TaskRegister) -> None:
    """Register the task's gym id with its env class, episode limit and config."""
    register(TASK_ID, "{{ cookiecutter.package_name }}.task:{{ cookiecutter.class_name }}Env",
             max_episode_steps=MAX_EPISODE_STEPS, config=str(CONFIG_PATH),
             description="{{ cookiecutter.description }}")


@hookimpl
def embodichain_register_robots(register: RobotRegister) -> None:
    """Register the task's arm, so configs can select it by ``class_type``."""
    register("{{ cookiecutter.class_name }}Arm", "{{ cookiecutter.package_name }}.task:{{ cookiecutter.class_name }}ArmCfg")
