"""The core's own registrations (provider ``"embodichain-core"``), a plugin module like any
other: the ``embodichain`` subcommands and the demo task, as lazy ``"module:attr"`` strings so
that ``embodichain --help`` imports no command module and no env class."""

from __future__ import annotations

from pathlib import Path

from embodichain_core.plugins.hookspecs import CommandRegister, TaskRegister, hookimpl

#: name -> (target, help) of the built-in CLI commands.
BUILTIN_COMMANDS: dict[str, tuple[str, str]] = {
    "list": (
        "embodichain_core.cli.list_cmd:main",
        "List installed plugins, tasks, functors, robots, solvers, sensors, assets, commands or viewers",
    ),
    "run-env": (
        "embodichain_core.cli.run_env:main",
        "Run a task id or a JSON/YAML gym config (data generation, preview)",
    ),
    "decompose": ("embodichain_core.cli.decompose:main", "Convex-decompose a mesh or the meshes of a URDF with CoACD"),
    "new": ("embodichain_core.cli.new_cmd:main", "Create a new task or functor plugin from a template"),
    "bench": ("embodichain_core.cli.bench:main", "Measure env throughput and overhead"),
}
#: The demo task (``embodichain_core.demo``): its gym id and its gym config, which
#: ``embodichain run-env`` runs when given neither a task id nor a config.
DEMO_TASK_ID = "EmbodiChainDemo-v0"
DEMO_CONFIG = Path(__file__).resolve().parents[1] / "demo" / "demo_scene.json"


@hookimpl
def embodichain_register_commands(register: CommandRegister) -> None:
    """Register the built-in ``embodichain`` subcommands."""
    for name, (target, help_text) in BUILTIN_COMMANDS.items():
        register(name, target, help=help_text)


@hookimpl
def embodichain_register_tasks(register: TaskRegister) -> None:
    """Register the demo task: a 7-DoF arm at a table with three cubes and a point light."""
    description = "The built-in demo: a 7-DoF arm at a table with three cubes and a point light"
    register(DEMO_TASK_ID, "embodichain_core.demo:DemoSceneEnv", config=str(DEMO_CONFIG), description=description)
