"""The docs site: it builds strictly, its nav covers docs/, the CLI page is up to date, and
every hookspec, registered functor and registered task is documented.

The functor and task checks cover what the plugins of this repository (``plugins/*``)
register once installed; each is skipped while those plugins register nothing.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Iterable

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
#: Pages of which at least one must name each hook specification.
HOOK_PAGES = ("plugins.md", "writing_plugins.md")


def nav_pages(nav: Any) -> list[str]:
    """Every page file in an mkdocs ``nav`` (nested sections included)."""
    if isinstance(nav, str):
        return [nav]
    if isinstance(nav, list):
        return [page for item in nav for page in nav_pages(item)]
    if isinstance(nav, dict):
        return [page for value in nav.values() for page in nav_pages(value)]
    return []


def repo_plugin_names() -> set[str]:
    """Distribution (= provider) names of the plugins kept in plugins/."""
    names = set()
    for pyproject in REPO.glob("plugins/*/pyproject.toml"):
        match = re.search(r'^name\s*=\s*"([^"]+)"', pyproject.read_text(encoding="utf-8"), re.MULTILINE)
        names.update([match.group(1)] if match else [])
    return names


def undocumented(names: Iterable[str], page: Path) -> list[str]:
    """The names that do not appear in ``page`` as whole words."""
    text = page.read_text(encoding="utf-8") if page.exists() else ""
    return sorted(n for n in names if not re.search(rf"(?<![\w-]){re.escape(n)}(?![\w-])", text))


def registered(kind: str) -> list[str]:
    """Names of ``kind`` registered by this repository's plugins (installed and loaded)."""
    from embodichain_core.plugins import get_registry

    providers = repo_plugin_names()
    return [e.name for e in get_registry(kind).entries() if e.provider in providers]


def load_generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_cli_docs", REPO / "scripts" / "gen_cli_docs.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_nav_lists_every_page_once() -> None:
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    listed = nav_pages(config["nav"])
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    assert not sorted(pages - set(listed)), f"add {sorted(pages - set(listed))} to the nav in mkdocs.yml"
    assert not sorted(set(listed) - pages), f"the nav in mkdocs.yml lists missing pages {sorted(set(listed) - pages)}"
    assert len(listed) == len(set(listed)), "a page is listed twice in the nav"


def test_mkdocs_build_is_strict_and_passes(tmp_path: Path) -> None:
    pytest.importorskip("mkdocs", reason="mkdocs is in the test extra")
    config = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    assert config["strict"] is True and config["theme"]["name"] == "material"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                         cwd=REPO, capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 0, f"mkdocs build --strict failed:\n{out.stdout}\n{out.stderr}"
    assert (tmp_path / "site" / "writing_plugins" / "index.html").is_file()


def test_cli_reference_is_generated_from_the_parsers() -> None:
    generated = load_generator().render()
    committed = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert committed == generated, "docs/cli.md is out of date: run .venv/bin/python scripts/gen_cli_docs.py"


def test_cli_reference_covers_every_builtin_command_and_option() -> None:
    from embodichain_core.cli import new_cmd
    from embodichain_core.plugins.builtin import BUILTIN_COMMANDS

    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert all(f"## `embodichain {name}`" in text for name in BUILTIN_COMMANDS)
    for sub in ("task", "functor"):
        assert f"### `embodichain new {sub}`" in text
    assert "`--no-input`" in text and "`--kind`" in text and "`-o`, `--output-dir` `DIR`" in text
    assert new_cmd.build_parser().prog == "embodichain new"


def test_every_hookspec_is_documented() -> None:
    from embodichain_core.plugins import hookspecs

    specs = [name for name, obj in vars(hookspecs).items()
             if callable(obj) and getattr(obj, "embodichain_spec", None) is not None]
    assert len(specs) >= 6
    missing = set(specs)
    for page in HOOK_PAGES:
        missing &= set(undocumented(specs, DOCS / page))
    assert not missing, f"neither of docs/{' and docs/'.join(HOOK_PAGES)} names the hook(s) {sorted(missing)}"


def test_every_registered_functor_is_in_the_catalogue() -> None:
    names = registered("functors")
    if not names:
        pytest.skip("no functor registered by the plugins in plugins/ (none installed yet)")
    missing = undocumented(names, DOCS / "functor_catalogue.md")
    assert not missing, f"docs/functor_catalogue.md does not list the functor(s) {missing}"


def test_every_registered_task_is_in_the_task_list() -> None:
    names = registered("tasks")
    if not names:
        pytest.skip("no task registered by the plugins in plugins/ (none installed yet)")
    missing = undocumented(names, DOCS / "tasks.md")
    assert not missing, f"docs/tasks.md does not list the task(s) {missing}"


def test_meta_checks_catch_a_missing_name(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("`randomize_light` and PushCube-v1, see `joint_pos_rel`.\n")
    assert undocumented(["randomize_light", "PushCube-v1", "joint_pos", "PushCube-v10"], page) == [
        "PushCube-v10", "joint_pos"]
    assert undocumented(["anything"], tmp_path / "absent.md") == ["anything"]
