"""``embodichain new``: create a task or functor plugin package from a template.

The cookiecutter templates ship with embodichain-core (package
:mod:`embodichain_core.templates`, source in the repository's ``templates/``). Names are
checked before anything is written; every option given on the command line is passed to
cookiecutter as ``extra_context``, and the other values derive from the name. Nothing is
asked when ``--no-input`` is given or stdin is not a terminal.

cookiecutter is not a required dependency of the core: it comes with the ``new`` extra
(``pip install "embodichain-core[new]"``); without it the command stops with a message
saying so (:data:`INSTALL_HINT`).

Exit codes: 0 created, 1 the output directory exists, baking failed or cookiecutter is
missing, 2 invalid names.

Example:
    $ embodichain new task push_cube --no-input
    $ embodichain new functor cube_height --kind observation --output-dir plugins
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable, Sequence

PROG = "embodichain new"
FUNCTOR_KINDS = ("observation", "reward", "event", "randomization")
#: How to install what ``embodichain new`` needs beyond the core (the ``new`` extra).
INSTALL_HINT = 'pip install "embodichain-core[new]"'


EPILOG = f"""**Requirements.** The templates are rendered by cookiecutter, which comes with the
core's `new` extra: `{INSTALL_HINT}` (`scripts/setup_env.sh` installs
it). Without it the command exits with 1 and says so."""


class MissingTemplateEngineError(ImportError):
    """cookiecutter, which renders the templates, is not installed (the ``new`` extra)."""


def require_cookiecutter() -> Callable[..., str]:
    """The ``cookiecutter()`` function, imported on demand.

    Returns:
        ``cookiecutter.main.cookiecutter``.

    Raises:
        MissingTemplateEngineError: cookiecutter is not installed; the message names
            :data:`INSTALL_HINT`.
    """
    try:
        from cookiecutter.main import cookiecutter
    except ImportError as err:
        raise MissingTemplateEngineError(
            f"cookiecutter is not installed; embodichain new renders its templates with it. "
            f"Install it with: {INSTALL_HINT}",
            name="cookiecutter",
        ) from err
    return cookiecutter


def build_parser() -> argparse.ArgumentParser:
    """The ``embodichain new`` parser, with one subcommand per template."""
    parser = argparse.ArgumentParser(
        prog=PROG, description="Create a plugin package (installable, with tests) from a template.", epilog=EPILOG
    )
    sub = parser.add_subparsers(dest="template", metavar="<template>", title="templates", required=True)
    task = sub.add_parser(
        "task",
        help="a task: an EmbodiedEnv subclass registered as a gym id",
        description="Create a task plugin: an EmbodiedEnv subclass with its config (Python and JSON), "
        "registered through the 'embodichain' entry point, and its tests.",
    )
    task.add_argument(
        "name",
        metavar="NAME",
        help="task name: words of letters and digits joined by '-' or '_' "
        "(push_cube gives PushCube-v0 in embodichain-push-cube)",
    )
    task.add_argument(
        "--task-id",
        help="gymnasium id, Name-vN without a namespace (the namespace is the package's distribution; "
        "default: <ClassName>-v0)",
    )
    task.add_argument("--max-episode-steps", type=int, metavar="N", help="episode length (default: 100)")
    functor = sub.add_parser(
        "functor",
        help="an observation, reward, event or randomization functor",
        description="Create a functor plugin: one functor registered through the 'embodichain' "
        "entry point, and its tests.",
    )
    functor.add_argument(
        "name",
        metavar="NAME",
        help="functor name: a lowercase identifier such as cube_height "
        "(randomization functors get the prefix randomize_)",
    )
    functor.add_argument("--kind", choices=FUNCTOR_KINDS, help="functor kind (default: observation)")
    for p in (task, functor):
        _add_common(p)
    return parser


def _add_common(parser: argparse.ArgumentParser) -> None:
    """The options every template takes."""
    parser.add_argument("--description", help="one-line description")
    parser.add_argument("--author", help="author written into pyproject.toml")
    parser.add_argument(
        "-o", "--output-dir", default=".", metavar="DIR", help="where the package directory is created (default: .)"
    )
    parser.add_argument(
        "--no-input", action="store_true", help="do not prompt; use the options and the defaults derived from NAME"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="write into an existing package directory, replacing its files"
    )


def context_from_args(args: argparse.Namespace) -> tuple[dict[str, Any], list[str]]:
    """``(extra_context, errors)``: the values given on the command line, and the problems
    of the full set of names derived from them (empty when valid)."""
    from embodichain_core.templates import names

    common = {"description": args.description, "author": args.author}
    if args.template == "task":
        given = {"task_name": args.name, "task_id": args.task_id, "max_episode_steps": args.max_episode_steps, **common}
        full = names.task_context(args.name, **given)
        errors = names.validate_task_context(full)
    else:
        full = names.functor_context(args.name, args.kind)
        given = {"functor_name": full["functor_name"], "kind": args.kind, **common}
        full.update({k: v for k, v in given.items() if v is not None})
        errors = names.validate_functor_context(full)
    return {k: v for k, v in given.items() if v is not None}, errors


def bake(
    template: str,
    extra_context: dict[str, Any],
    output_dir: str | Path = ".",
    *,
    no_input: bool = True,
    overwrite: bool = False,
) -> Path:
    """Render the shipped template ``template`` (``"task"``/``"functor"``) into ``output_dir``.

    The user's cookiecutter config is not read and no replay file is left behind.

    Returns:
        The created package directory.

    Raises:
        cookiecutter.exceptions.OutputDirExistsException: the directory exists and
            ``overwrite`` is false.
        cookiecutter.exceptions.FailedHookException: the template's name checks failed.
        MissingTemplateEngineError: cookiecutter is not installed.
    """
    cookiecutter = require_cookiecutter()

    from embodichain_core.templates import template_dir

    Path(output_dir).mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="embodichain-new-") as replay_dir:
        created = cookiecutter(
            str(template_dir(template)),
            no_input=no_input,
            extra_context=extra_context,
            output_dir=str(output_dir),
            overwrite_if_exists=overwrite,
            default_config={"replay_dir": replay_dir},  # type: ignore[arg-type]
        )
    return Path(created)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``embodichain new``; returns the exit code."""
    args = build_parser().parse_args(argv)
    extra_context, errors = context_from_args(args)
    if errors:
        for error in errors:
            print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    no_input = args.no_input or not sys.stdin.isatty()
    try:
        require_cookiecutter()
    except MissingTemplateEngineError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 1
    try:
        created = bake(args.template, extra_context, args.output_dir, no_input=no_input, overwrite=args.overwrite)
    except Exception as err:  # cookiecutter's errors, reported without a traceback
        return _report_failure(err)
    print(_next_steps(args.template, created))
    return 0


def _report_failure(err: Exception) -> int:
    """Print a baking failure without a traceback; return the exit code."""
    from cookiecutter.exceptions import FailedHookException, OutputDirExistsException

    if isinstance(err, OutputDirExistsException):
        reason = str(err).removeprefix("Error: ")
        print(f"{PROG}: error: {reason}; pass --overwrite to write into it", file=sys.stderr)
        return 1
    if isinstance(err, FailedHookException):
        print(f"{PROG}: error: the template rejected the names (see the errors above)", file=sys.stderr)
        return 2
    print(f"{PROG}: error: {type(err).__name__}: {err}", file=sys.stderr)
    return 1


def _next_steps(template: str, created: Path) -> str:
    """What to do with the new package."""
    listing = "tasks" if template == "task" else "functors"
    return "\n".join(
        [
            f"created {template} plugin {created}",
            "next:",
            f"  cd {created}",
            "  pip install -e '.[test]'    # the entry point makes it discoverable",
            "  pytest",
            f"  embodichain list {listing}",
        ]
    )
