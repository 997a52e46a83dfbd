"""``embodichain list {plugins,tasks,functors,robots,solvers,sensors,assets,commands,viewers}``.

Prints an aligned table (or JSON with ``--json``) of what the installed plugins
registered, with the provider of every row. Lazy targets are shown as ``"module:attr"``
text and are not imported, unless ``--resolve`` asks to fill in missing descriptions
from docstrings.

Names several plugins register (clashes) are kept once per provider; their rows are
marked with ``*`` and a footer lists the qualified names to use. ``list plugins`` ends
with every clash. JSON rows carry ``qualified_name`` and ``ambiguous``.

Example:
    $ embodichain list functors --provider embodichain-functors
    $ embodichain list plugins --json
"""

from __future__ import annotations

import argparse
import json
from typing import Any, Callable, Sequence

from embodichain_core.plugins.registry import RegistryEntry, TargetImportError, describe_target

WHAT = ("plugins", "tasks", "functors", "robots", "solvers", "sensors", "assets", "commands", "viewers")

#: (header, key) of the table columns of every listing.
COLUMNS: dict[str, list[tuple[str, str]]] = {
    "plugins": [
        ("NAME", "name"),
        ("VERSION", "version"),
        ("STATUS", "status"),
        ("REGISTERED", "summary"),
        ("CLASHES", "clash_count"),
    ],
    "tasks": [
        ("ID", "name"),
        ("ENTRY POINT", "entry_point"),
        ("MAX STEPS", "max_episode_steps"),
        ("PROVIDER", "provider"),
        ("DESCRIPTION", "description"),
    ],
    "functors": [
        ("NAME", "name"),
        ("KIND", "kind"),
        ("CATEGORY", "category"),
        ("PROVIDER", "provider"),
        ("DESCRIPTION", "description"),
    ],
    "robots": [("NAME", "name"), ("CONFIG CLASS", "cfg_class"), ("PROVIDER", "provider")],
    "solvers": [("NAME", "name"), ("SOLVER CLASS", "solver_class"), ("PROVIDER", "provider")],
    "sensors": [
        ("SENSOR TYPE", "name"),
        ("CONFIG CLASS", "cfg_class"),
        ("SENSOR CLASS", "sensor_class"),
        ("PROVIDER", "provider"),
    ],
    "assets": [("NAME", "name"), ("ROOT", "root"), ("PROVIDER", "provider")],
    "commands": [("COMMAND", "name"), ("TARGET", "target"), ("PROVIDER", "provider"), ("HELP", "help")],
    "viewers": [("VIEWER", "name"), ("OPENER", "target"), ("PROVIDER", "provider"), ("DESCRIPTION", "description")],
}


EPILOG = """\
**Output.** One row per registered entry, with the plugin that provides it (`PROVIDER`).
Two plugins may register the same name; both stay loaded, and the bare name is then
ambiguous: its rows are marked `*`, and a footer lists the qualified names that always
resolve (`<plugin>/<name>`; for tasks that is the gymnasium id):

```text
NAME            KIND   CATEGORY  PROVIDER              DESCRIPTION
shared_event *  event  -         embodichain-functors  ...
shared_event *  event  -         my-plugin             ...

* provided by several plugins: the bare name is ambiguous; use the qualified name:
  embodichain-functors/shared_event  (embodichain-functors)
  my-plugin/shared_event  (my-plugin)
```

`list plugins` shows each plugin's version, status, what it registered and its number of
clashes, then the failed plugins and every name clash (names, providers, qualified
names). With `--json`, entry rows carry
`qualified_name` and `ambiguous`; plugin rows carry `entry_point` and `clashes`.
"""


def build_parser() -> argparse.ArgumentParser:
    """The ``embodichain list`` parser."""
    parser = argparse.ArgumentParser(
        prog="embodichain list",
        description="List what the installed plugins provide.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("what", nargs="?", default="plugins", choices=WHAT, help="what to list (default: plugins)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--provider", metavar="NAME", help="only entries registered by this plugin")
    parser.add_argument(
        "--resolve", action="store_true", help="import the targets to fill in missing descriptions (slower)"
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="show the tracebacks of failed plugins")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``embodichain list``; returns the exit code."""
    args = build_parser().parse_args(argv)
    rows = collect(args.what, provider=args.provider, resolve=args.resolve)
    if args.json:
        print(json.dumps(rows, indent=2, default=str))
        return 0
    if not rows:
        print(f"no {args.what} registered" + (f" by {args.provider!r}" if args.provider else ""))
    else:
        print(format_table(COLUMNS[args.what], [_marked(r) for r in rows]))
    if args.what == "plugins":
        _print_failures(rows, verbose=args.verbose)
        _print_plugin_clashes(args.provider)
    else:
        _print_row_clashes(rows)
    return 0


def _marked(row: dict[str, Any]) -> dict[str, Any]:
    """The row with ``*`` after an ambiguous name."""
    return {**row, "name": f"{row['name']} *"} if row.get("ambiguous") else row


def _print_row_clashes(rows: list[dict[str, Any]]) -> None:
    ambiguous = [r for r in rows if r.get("ambiguous")]
    if ambiguous:
        print("\n* provided by several plugins: the bare name is ambiguous; use the qualified name:")
        for row in ambiguous:
            print(f"  {row['qualified_name']}  ({row['provider']})")


def _print_plugin_clashes(provider: str | None) -> None:
    from embodichain_core.plugins import name_clashes

    clashes = name_clashes(provider)
    if clashes:
        print("\nname clashes (both plugins stay loaded; use the qualified names):")
        for clash in clashes:
            print(f"  {clash}")


def collect(what: str, *, provider: str | None = None, resolve: bool = False) -> list[dict[str, Any]]:
    """The rows of one listing as plain dicts (what ``--json`` prints)."""
    from embodichain_core.plugins import get_registry, list_plugins

    if what == "plugins":
        rows = [_plugin_row(info) for info in list_plugins()]
        return [r for r in rows if provider in (None, r["name"])]
    registry = get_registry(what)
    clashes = registry.clashes()
    entries = [e for e in registry.entries() if provider in (None, e.provider)]
    return [
        {**_ROWS[what](e, resolve), "qualified_name": registry.qualified_name(e), "ambiguous": e.name in clashes}
        for e in entries
    ]


def format_table(columns: list[tuple[str, str]], rows: list[dict[str, Any]]) -> str:
    """Left-aligned columns separated by two spaces; ``None`` shows as ``-``."""
    table = [[h for h, _ in columns]] + [[_cell(r.get(k)) for _, k in columns] for r in rows]
    widths = [max(len(line[i]) for line in table) for i in range(len(columns))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip() for line in table]
    return "\n".join(lines)


def _cell(value: Any) -> str:
    return "-" if value is None or value == "" else str(value)


def _plugin_row(info: Any) -> dict[str, Any]:
    from embodichain_core.plugins import name_clashes

    summary = " ".join(f"{k}={len(v)}" for k, v in sorted(info.registered.items()))
    clashes = [
        {"kind": c.kind, "name": c.name, "providers": list(c.providers), "qualified": list(c.qualified)}
        for c in name_clashes(info.name)
    ]
    return {
        "name": info.name,
        "version": info.version,
        "status": info.status,
        "module": info.module,
        "entry_point": info.entry_point,
        "registered": info.registered,
        "summary": summary,
        "clashes": clashes,
        "clash_count": len(clashes) or None,
        "error": info.error_summary,
        "traceback": info.error,
    }


def _print_failures(rows: list[dict[str, Any]], *, verbose: bool) -> None:
    failed = [r for r in rows if r["status"] == "failed"]
    if not failed:
        return
    print("\nfailed plugins:")
    for row in failed:
        print(f"  {row['name']}: {row['error']}")
        if verbose:
            print("    " + row["traceback"].rstrip().replace("\n", "\n    "))
    if not verbose:
        print("(run with -v for the tracebacks)")


def _description(entry: RegistryEntry, resolve: bool) -> str:
    if resolve and not entry.resolved:
        try:
            entry.resolve()
        except TargetImportError as err:
            return f"(cannot import: {err.__cause__!r})"
    return entry.description


def _base(entry: RegistryEntry) -> dict[str, Any]:
    return {"name": entry.name, "provider": entry.provider}


def _task_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {
        **_base(entry),
        "entry_point": entry.target_repr,
        "max_episode_steps": entry.meta.get("max_episode_steps"),
        "kwargs": entry.meta.get("kwargs"),
        "config": entry.meta.get("config"),
        "description": _description(entry, resolve),
    }


def _functor_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {
        **_base(entry),
        "kind": entry.meta.get("kind"),
        "category": entry.meta.get("category"),
        "target": entry.target_repr,
        "description": _description(entry, resolve),
    }


def _robot_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {**_base(entry), "cfg_class": entry.target_repr}


def _solver_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {**_base(entry), "solver_class": entry.target_repr}


def _sensor_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {
        **_base(entry),
        "cfg_class": entry.target_repr,
        "sensor_class": describe_target(entry.meta.get("sensor_class")),
    }


def _asset_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    root = entry.target
    return {**_base(entry), "root": f"{describe_target(root)}()" if callable(root) else str(root)}


def _command_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {**_base(entry), "target": entry.target_repr, "help": entry.meta.get("help") or entry.description}


def _viewer_row(entry: RegistryEntry, resolve: bool) -> dict[str, Any]:
    return {**_base(entry), "target": entry.target_repr, "description": _description(entry, resolve)}


_ROWS: dict[str, Callable[[RegistryEntry, bool], dict[str, Any]]] = {
    "tasks": _task_row,
    "functors": _functor_row,
    "robots": _robot_row,
    "solvers": _solver_row,
    "sensors": _sensor_row,
    "assets": _asset_row,
    "commands": _command_row,
    "viewers": _viewer_row,
}
