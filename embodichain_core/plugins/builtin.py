"""The core's own registrations: a plugin module like any other.

Registered by :func:`~embodichain_core.plugins.manager.load_plugins` under the
name ``"embodichain-core"``. Every target is a lazy ``"module:function"`` string,
so ``embodichain --help`` imports none of the command modules.
"""

from __future__ import annotations

from embodichain_core.plugins.hookspecs import CommandRegister, hookimpl

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


@hookimpl
def embodichain_register_commands(register: CommandRegister) -> None:
    """Register the built-in ``embodichain`` subcommands."""
    for name, (target, help_text) in BUILTIN_COMMANDS.items():
        register(name, target, help=help_text)
