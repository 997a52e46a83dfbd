"""The command lists of the docs name every command and subcommand there is.

* README.md's CLI synopsis and docs/cli.md name every installed ``embodichain`` command of
  the core and of this repository's plugins;
* a command's one-line summary (its registered help, the cli.md tables) and any docs table
  row that introduces ``embodichain <command>`` name each of its subcommands;
* the plugin templates spell qualified registry names ``<plugin>/<name>`` (``:`` is an error).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from test_docs import CHECKED_PAGES, DOCS, REPO, command_parsers, rel, repo_plugin_names, split_markdown


def repo_commands() -> dict[str, str]:
    """``name -> help`` of the commands of the core and of the plugins in plugins/."""
    from embodichain_core.plugins import command_registry

    providers = repo_plugin_names() | {"embodichain-core"}
    entries = command_registry().entries()
    return {e.name: str((e.meta or {}).get("help", "")) for e in entries if e.provider in providers}


def subcommands(parser: argparse.ArgumentParser) -> list[str]:
    return [name for a in parser._actions if isinstance(a, argparse._SubParsersAction) for name in a.choices]


def section(page: Path, heading: str) -> str:
    """The text of ``page`` from ``heading`` to the next heading of the same level."""
    text = page.read_text(encoding="utf-8")
    level = heading.split(" ")[0]
    match = re.search(rf"^{re.escape(heading)}\s*$(.*?)(?=^{level} |\Z)", text, re.MULTILINE | re.DOTALL)
    assert match, f"{rel(page)} has no section {heading!r}"
    return match.group(1)


def missing_commands(text: str, names: list[str]) -> list[str]:
    return sorted(n for n in names if not re.search(rf"embodichain {re.escape(n)}(?![\w-])", text))


def test_the_readme_cli_section_and_cli_md_name_every_command() -> None:
    names = list(repo_commands())
    assert {"run-env", "list", "new", "bench", "decompose"} <= set(names), names
    missing = missing_commands(section(REPO / "README.md", "## CLI"), names)
    assert not missing, f"README.md's CLI section does not show {missing}"
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    missing = [n for n in names if f"## `embodichain {n}`" not in cli]
    assert not missing, f"docs/cli.md has no section for {missing}: run scripts/gen_cli_docs.py"


def test_a_command_summary_names_every_subcommand() -> None:
    parsers, helps = command_parsers(), repo_commands()
    wrong = []
    for name, parser in parsers.items():
        for sub in subcommands(parser):
            if name in helps and not re.search(rf"\b{re.escape(sub)}\b", helps[name]):
                wrong.append(f"the help of `embodichain {name}` ({helps[name]!r}) does not name {sub!r}")
    assert not wrong, "\n".join(wrong)


def intro_rows(page: Path) -> list[tuple[int, str, str]]:
    """``(line, command, row)`` of each table row whose first cell is ``embodichain <command>``."""
    _, prose = split_markdown(page.read_text(encoding="utf-8"))
    rows = []
    for number, line in prose:
        match = re.match(r"^\|\s*`embodichain ([\w-]+)`\s*\|", line)
        if match:
            rows.append((number, match.group(1), line))
    return rows


def test_a_table_row_introducing_a_command_names_its_subcommands() -> None:
    parsers = command_parsers()
    rows = [(page, *row) for page in CHECKED_PAGES for row in intro_rows(page)]
    assert any(name == "dataset" for _, _, name, _ in rows), "docs/datasets.md no longer introduces the command"
    wrong = [
        f"{rel(page)}:{n}: the row of `embodichain {name}` does not name {sub!r}"
        for page, n, name, row in rows
        if name in parsers
        for sub in subcommands(parsers[name])
        if not re.search(rf"`{re.escape(sub)}\b", row)
    ]
    assert not wrong, "\n".join(wrong)


def test_templates_spell_qualified_names_with_a_slash() -> None:
    bad = []
    for path in sorted((REPO / "templates").rglob("*")):
        if path.is_file() and path.suffix in {".py", ".md", ".toml", ".json", ".txt"}:
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if re.search(r"distribution_name \}\}:<", line):
                    bad.append(f"{path.relative_to(REPO)}:{number}: {line.strip()}")
    assert not bad, "qualified names are '<plugin>/<name>':\n" + "\n".join(bad)


def test_the_checks_catch_what_they_look_for() -> None:
    assert missing_commands("embodichain run-env X\nembodichain new-thing", ["run-env", "new"]) == ["new"]
    parser = argparse.ArgumentParser()
    parser.add_subparsers().add_parser("replay")
    assert subcommands(parser) == ["replay"]
