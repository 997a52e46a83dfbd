"""``embodichain``: the console script dispatching to registered subcommands.

Subcommands are ``"module:function"`` targets from the ``commands`` registry
(``function(argv: list[str]) -> int``), imported only when they run: neither
``embodichain --help`` nor ``embodichain --version`` imports a command module.
``embodichain <command> ...`` forwards the rest of the arguments verbatim, so
``embodichain <command> --help`` reaches the command's own parser.

A command is named by its bare name (``list``) or its qualified name
(``<plugin>/<name>``: ``embodichain-core/list``). A bare name that several plugins register is an
error naming every provider and the qualified forms.

Example:
    $ embodichain list tasks
    $ embodichain run-env --help
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Callable, Sequence

from embodichain_core.plugins.registry import AmbiguousNameError, Registry, TargetImportError
from embodichain_core.utils.suggest import did_you_mean

PROG = "embodichain"


def build_parser(commands: Registry) -> argparse.ArgumentParser:
    """The top-level parser: ``--help`` lists the commands, ``--version`` prints the version."""
    from embodichain_core import __version__

    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Configuration-driven robot-learning environments on MuJoCo.",
        epilog=f"Run '{PROG} <command> --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"embodichain-core {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>", title="commands")
    clashes = commands.clashes()
    listed = {
        name: f"(ambiguous: provided by {', '.join(providers)}; use a qualified name)"
        for name, providers in clashes.items()
    }
    for entry in commands.entries():
        name = commands.qualified_name(entry) if entry.name in clashes else entry.name
        listed[name] = entry.meta.get("help") or entry.description
    for name in sorted(listed):
        sub.add_parser(name, help=listed[name], add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``embodichain`` with ``argv`` (default: ``sys.argv[1:]``); return the exit code."""
    from embodichain_core.plugins import command_registry

    args = list(sys.argv[1:] if argv is None else argv)
    commands = command_registry()
    parser = build_parser(commands)
    if not args:
        parser.print_help()
        return 0
    if args[0].startswith("-"):
        return _run(lambda: _top_level(parser, args))
    try:
        entry = commands.find(args[0])
    except AmbiguousNameError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 2
    if entry is None:
        parser.print_usage(sys.stderr)
        print(f"{PROG}: error: {_unknown(commands, args[0])}", file=sys.stderr)
        return 2
    try:
        command = entry.resolve()
    except TargetImportError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 1
    return _run(lambda: command(args[1:]))


def _unknown(commands: Registry, name: str) -> str:
    """``unknown command 'x'. Did you mean ...?`` (qualified names get the registry's message)."""
    if "/" in name:
        return str(commands.unknown(name))
    return f"unknown command {name!r}.{did_you_mean(name, commands.names())}"


def _top_level(parser: argparse.ArgumentParser, args: list[str]) -> int:
    """Handle ``--help`` / ``--version`` (they exit); anything else is a usage error."""
    parser.parse_args(args)
    parser.print_usage(sys.stderr)
    print(f"{PROG}: error: put the command before its options", file=sys.stderr)
    return 2


def _run(func: Callable[[], Any]) -> int:
    try:
        return exit_code(func())
    except SystemExit as exc:
        return exit_code(exc.code)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


def exit_code(code: Any) -> int:
    """``None`` -> 0, ints as they are, anything else is printed and gives 1."""
    if code is None:
        return 0
    if isinstance(code, int):
        return int(code)
    print(code, file=sys.stderr)
    return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
