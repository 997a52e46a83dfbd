"""One home per functor kind: the public modules export every registered functor and every
name the docs show, the registrations are one line each, and their descriptions are read
from the docstrings without importing a functor module."""

from __future__ import annotations

import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

from embodichain_core.plugins import functor_registry
from embodichain_core.plugins.registry import first_doc_line

from embodichain_functors.catalogue import FUNCTORS, REGISTRATIONS, doc_lines_of_file, source_files

REPO = Path(__file__).resolve().parents[3]
#: pages whose code or module tables show names of the public modules
PAGES = [
    REPO / "docs" / "functors.md",
    REPO / "docs" / "tutorial_modular_env.md",
    REPO / "plugins" / "embodichain-functors" / "README.md",
]
#: public helpers (not functors) of the kind modules, importable since before the modules became packages
HELPERS = {
    "embodichain_functors.events": ["resolve_uids", "resolve_dict", "get_pose"],
    "embodichain_functors.randomization": ["get_random_pose"],
    "embodichain_functors.rewards": ["position_of", "rotation_of", "target_positions"],
}


@pytest.mark.parametrize("row", FUNCTORS, ids=[row[0] for row in FUNCTORS])
def test_every_registered_functor_is_exported_by_its_public_module(row) -> None:
    name, target, _, _, description = row
    module_name, attr = target.split(":")
    module = importlib.import_module(module_name)
    assert attr in module.__all__, f"{name}: missing from {module_name}.__all__ (its module's __all__)"
    assert getattr(module, attr) is functor_registry().get(name)
    assert description, f"{name}: no docstring found in the sources of {module_name}"
    assert description == first_doc_line(getattr(module, attr)), f"{name}: description is not the docstring's"


@pytest.mark.parametrize("module_name", sorted(HELPERS))
def test_public_helpers_stay_importable(module_name) -> None:
    module = importlib.import_module(module_name)
    for name in HELPERS[module_name]:
        assert callable(getattr(module, name, None)), f"{module_name}.{name} is gone"


def test_every_functor_a_public_module_exports_is_registered() -> None:
    """A functor (a docstring with a ``"func"`` config example) written without its registration line."""
    registered = {row[1] for row in FUNCTORS}
    unregistered = []
    for module_name in REGISTRATIONS:
        module = importlib.import_module(module_name)
        for name in module.__all__:
            doc = inspect.getdoc(getattr(module, name)) or ""
            if '"func"' in doc and f"{module_name}:{name}" not in registered:
                unregistered.append(f"{module_name}.{name}")
    assert not unregistered, f"exported functors without a line in catalogue.REGISTRATIONS: {unregistered}"


def _code(text: str) -> str:
    return "\n".join(re.findall(r"```\w*\n(.*?)```", text, re.DOTALL))


def documented_names(page: Path) -> list[tuple[str, str]]:
    """``(module, name)`` pairs a page shows: ``alias.name`` after ``import <module> as alias`` in
    its code blocks, and the backquoted names of a ``| `module` | ... |`` table row."""
    text = page.read_text(encoding="utf-8")
    code = _code(text)
    pairs = []
    for module, alias in re.findall(r"^\s*import (embodichain_functors\.\w+) as (\w+)", code, re.MULTILINE):
        pairs += [(module, name) for name in re.findall(rf"\b{alias}\.(\w+)", code)]
    for module, row in re.findall(r"^\| `(embodichain_functors\.\w+)` \|(.*)\|\s*$", text, re.MULTILINE):
        pairs += [(module, name) for name in re.findall(r"`(\w+)`", row)]
    return sorted(set(pairs))


def test_every_public_name_the_docs_show_imports() -> None:
    pairs = [(page, pair) for page in PAGES for pair in documented_names(page)]
    assert len(pairs) >= 15, f"only {len(pairs)} documented names found: the parsing broke"
    missing = [
        f"{page.name}: {module}.{name}"
        for page, (module, name) in pairs
        if not hasattr(importlib.import_module(module), name)
    ]
    assert not missing, f"names the docs show that do not import: {missing}"


def test_documented_names_parse_aliases_and_module_tables(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(
        "```python\nimport embodichain_functors.events as ev\nev.replace_assets_from_group\n```\n"
        "| `embodichain_functors.rewards` | `success_reward`, penalties |\n"
    )
    assert documented_names(page) == [
        ("embodichain_functors.events", "replace_assets_from_group"),
        ("embodichain_functors.rewards", "success_reward"),
    ]


def test_doc_lines_are_read_from_the_source(tmp_path: Path) -> None:
    source = tmp_path / "mod.py"
    source.write_text(
        '@validated(check)\ndef a(env: Any,\n      x: int = 1) -> None:\n    """First line of a.\n\n    More.\n    """\n\n\n'
        "def b(env):\n    return 1\n\n\n"
        "class C(Base):\n    '''\n    C, on the next line.\n    '''\n\n    def m(self):\n"
        '        """Not the class."""\n\n\n'
        'def d(\n    env: Any,\n    x: int = 1,\n) -> None:\n    """D, after a signature closed at column 0."""\n'
    )
    assert doc_lines_of_file(source) == {
        "a": "First line of a.",
        "b": "",
        "C": "C, on the next line.",
        "d": "D, after a signature closed at column 0.",
    }


def test_source_files_of_packages_and_modules() -> None:
    names = {p.name for p in source_files("embodichain_functors.events")}
    assert {"__init__.py", "assets.py", "settling.py"} <= names
    names = {p.name for p in source_files("embodichain_functors.actions")}
    assert names == {"__init__.py", "base.py", "drive.py", "eef.py", "position.py"}
    assert [p.name for p in source_files("embodichain_functors.catalogue")] == ["catalogue.py"]


def test_registering_imports_no_functor_module() -> None:
    script = (
        "import sys\nfrom embodichain_core.plugins import functor_registry\n"
        "assert functor_registry().entry('randomize_light').meta['description']\n"
        "print(sorted(m for m in sys.modules if m.startswith('embodichain_functors')))\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == [
        "['embodichain_functors',",
        "'embodichain_functors.catalogue',",
        "'embodichain_functors.plugin']",
    ]
