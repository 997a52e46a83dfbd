"""docs/architecture.md against the code: its folder tree and its layer rules.

The folder tree is the fenced block of the page that starts with ``embodichain_core/``: every
name it lists must exist, and every package of ``embodichain_core/`` and every module at its
top level must be listed. The layer rules are the page's table ``| layer | modules | may import |``
and its table of allowed upward imports ``| importer | imports | why |`` (when it has one): every ``import`` and
``from ... import`` statement of ``embodichain_core/**`` (function-local ones included, those
under ``if TYPE_CHECKING:`` not) must go from a module to its own layer, to a layer its row
allows, or be listed as an upward import; and every listed upward import must still exist.

The core knows no plugin: no module of ``embodichain_core/**`` imports a plugin package
(the ``embodichain_*`` packages of ``plugins/*/`` and ``tests/fixture_plugins/*/``), by an
import statement (function-local ones included, ``if TYPE_CHECKING:`` ones not) or by
``importlib.import_module`` / ``__import__`` of a constant name.
"""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path
from typing import Iterator, NamedTuple

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = "embodichain_core"
DOC = ROOT / "docs" / "architecture.md"


class Import(NamedTuple):
    importer: str  # dotted module name relative to the package ("" for the package itself)
    target: str
    where: str  # path:line


def _rel(dotted: str) -> str:
    return "" if dotted == PKG else dotted.removeprefix(PKG + ".")


def _modules(pkg_dir: Path) -> dict[str, Path]:
    """Dotted names (relative to the package, ``""`` for its ``__init__``) of every module."""
    out = {}
    for path in sorted(pkg_dir.rglob("*.py")):
        parts = list(path.relative_to(pkg_dir).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _mapped_packages() -> set[str]:
    """Packages pyproject maps into ``embodichain_core`` from elsewhere (``templates/``)."""
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())
    package_dir = data.get("tool", {}).get("setuptools", {}).get("package-dir", {})
    return {_rel(name) for name in package_dir if name.startswith(PKG + ".")}


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """ids of the nodes inside ``if TYPE_CHECKING:`` bodies (annotations only, never run)."""
    inside: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and ast.unparse(node.test).split(".")[-1] == "TYPE_CHECKING":
            for stmt in node.body:
                inside.update(id(n) for n in ast.walk(stmt))
    return inside


def _resolve(modules: dict[str, Path], module: str, name: str | None) -> str:
    """The module an import statement loads: ``from a import b`` is ``a.b`` when that is a module."""
    if name is not None and f"{module}.{name}".strip(".") in modules:
        return f"{module}.{name}".strip(".")
    while module not in modules and module:
        module = module.rpartition(".")[0]
    return module


def _targets(node: ast.AST, package: str) -> Iterator[tuple[str, str | None]]:
    """``(module, name)`` pairs an import statement names, relative to ``embodichain_core``."""
    if isinstance(node, ast.Import):
        for alias in node.names:
            if alias.name == PKG or alias.name.startswith(PKG + "."):
                yield _rel(alias.name), None
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = [p for p in package.split(".") if p]
            base = base[: len(base) - (node.level - 1)]
            module = ".".join(base + ([node.module] if node.module else []))
        elif node.module == PKG or (node.module or "").startswith(PKG + "."):
            module = _rel(node.module or "")
        else:
            return
        for alias in node.names:
            yield module, alias.name


def core_imports() -> list[Import]:
    """Every import of one core module by another, TYPE_CHECKING blocks left out."""
    modules = _modules(ROOT / PKG)
    mapped = _mapped_packages()
    found = []
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(), filename=str(path))
        skip = _type_checking_nodes(tree)
        for node in ast.walk(tree):
            if id(node) in skip or not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            for module, alias in _targets(node, package):
                if module.split(".")[0] in mapped:
                    continue
                target = _resolve(modules, module, alias)
                if target != name:
                    found.append(Import(name, target, f"{path.relative_to(ROOT)}:{node.lineno}"))
    return found


#: The plugin packages the issue of the core boundary names; :func:`plugin_packages` must find them all.
KNOWN_PLUGIN_PACKAGES = {
    f"embodichain_{name}"
    for name in ("functors", "robots", "sensors", "lerobot", "tasks", "ray", "rl", "assets", "viewer")
}
_DYNAMIC_IMPORTS = ("import_module", "__import__")


def plugin_packages() -> set[str]:
    """The top-level packages of the plugins of this repository (and of the test fixture plugins)."""
    roots = [ROOT / "plugins", ROOT / "tests" / "fixture_plugins"]
    return {p.parent.name for root in roots for p in root.glob("*/embodichain_*/__init__.py")}


def _imported_names(node: ast.AST) -> list[str]:
    """The absolute module names an import statement or a constant dynamic import names."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if isinstance(node, ast.ImportFrom):
        return [node.module] if node.module and not node.level else []
    if isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
        func = ast.unparse(node.func).split(".")[-1]
        if func in _DYNAMIC_IMPORTS and isinstance(node.args[0].value, str):
            return [node.args[0].value]
    return []


def plugin_imports(pkg_dir: Path, packages: set[str]) -> list[str]:
    """``path:line: module`` of every import of one of ``packages`` under ``pkg_dir``,
    function-local ones included, ``if TYPE_CHECKING:`` ones left out."""
    found = []
    for path in sorted(pkg_dir.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        skip = _type_checking_nodes(tree)
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            for name in _imported_names(node):
                if name.split(".")[0] in packages:
                    found.append(f"{path.relative_to(pkg_dir.parent)}:{node.lineno}: {name}")
    return found


# --- the page -----------------------------------------------------------------------------


def _fenced_blocks(text: str) -> list[list[str]]:
    return [m.group(1).splitlines() for m in re.finditer(r"^```[a-z]*\n(.*?)^```", text, re.M | re.S)]


def tree_entries(text: str) -> list[str]:
    """Paths (relative to the repository) the folder tree lists, ``/`` ending a folder."""
    blocks = [b for b in _fenced_blocks(text) if b and b[0].strip() == f"{PKG}/"]
    assert len(blocks) == 1, f"architecture.md needs one fenced folder tree starting with {PKG}/"
    stack: list[str] = []
    entries = []
    for number, line in enumerate(blocks[0], 1):
        if not line.strip():
            continue
        indent = len(line) - len(line.lstrip(" "))
        assert indent % 2 == 0, f"tree line {number}: indent by two spaces: {line!r}"
        assert indent // 2 <= len(stack), f"tree line {number}: indented under no folder: {line!r}"
        del stack[indent // 2 :]
        names = [n.strip() for n in re.split(r"\s{2,}", line.strip())[0].split(",")]
        for name in names:
            assert re.fullmatch(r"[\w.\-]+/?", name), f"tree line {number}: not a file or folder name: {name!r}"
            entries.append("".join(stack) + name)
        if len(names) == 1 and names[0].endswith("/"):
            stack.append(names[0])
    return entries


def _table(text: str, header: tuple[str, ...], required: bool = True) -> list[list[str]]:
    """The rows of the page's Markdown table whose header cells are ``header`` (lower case)."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        cells = [c.strip().lower() for c in line.strip().strip("|").split("|")]
        if tuple(cells) == header:
            rows = []
            for row in lines[i + 2 :]:
                if not row.startswith("|"):
                    break
                rows.append([c.strip() for c in row.strip().strip("|").split("|")])
            return rows
    assert not required, f"architecture.md has no table with the header {' | '.join(header)}"
    return []


def _codes(cell: str) -> list[str]:
    return re.findall(r"`([^`]+)`", cell)


class Layers(NamedTuple):
    patterns: dict[str, str]  # module pattern -> layer
    allowed: dict[str, set[str]]  # layer -> layers it may import
    upward: dict[tuple[str, str], str]  # (importer, imported) -> why


def layer_rules(text: str) -> Layers:
    patterns: dict[str, str] = {}
    allowed: dict[str, set[str]] = {}
    for layer_cell, modules_cell, may_cell in _table(text, ("layer", "modules", "may import")):
        (layer,) = _codes(layer_cell) or [layer_cell]
        for pattern in _codes(modules_cell):
            assert pattern not in patterns, f"architecture.md: {pattern} is in two layers"
            patterns[pattern] = layer
        allowed[layer] = set(_codes(may_cell))
    unknown = {name for names in allowed.values() for name in names} - set(allowed)
    assert not unknown, f"architecture.md: 'may import' names layers that do not exist: {sorted(unknown)}"
    upward = {}
    for importer_cell, imported_cell, why in _table(text, ("importer", "imports", "why"), required=False):
        upward[(_codes(importer_cell)[0], _codes(imported_cell)[0])] = why
    return Layers(patterns, allowed, upward)


def layer_of(patterns: dict[str, str], module: str) -> str | None:
    """The layer of ``module``: its exact pattern, else the longest ``pkg.*`` pattern around it."""
    name = module or PKG
    if name in patterns:
        return patterns[name]
    best = None
    for pattern, layer in patterns.items():
        prefix = pattern.removesuffix(".*")
        if pattern.endswith(".*") and (name == prefix or name.startswith(prefix + ".")):
            if best is None or len(prefix) > len(best[0]):
                best = (prefix, layer)
    return best[1] if best else None


# --- the checks ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def text() -> str:
    return DOC.read_text()


def test_every_listed_path_exists(text: str) -> None:
    missing = [e for e in tree_entries(text) if not (ROOT / e).exists() or (e.endswith("/") != (ROOT / e).is_dir())]
    assert not missing, f"docs/architecture.md's folder tree lists what is not there: {missing}"


def test_every_package_and_top_level_module_is_listed(text: str) -> None:
    listed = set(tree_entries(text))
    pkg_dir = ROOT / PKG
    folders = {p.parent for p in pkg_dir.rglob("*.py") if p.parent != pkg_dir}
    wanted = {f"{d.relative_to(ROOT).as_posix()}/" for d in folders}
    wanted |= {p.relative_to(ROOT).as_posix() for p in pkg_dir.glob("*.py") if p.name != "__init__.py"}
    absent = sorted(wanted - listed)
    assert not absent, f"docs/architecture.md's folder tree leaves out: {absent}"


def test_every_module_has_a_layer(text: str) -> None:
    patterns = layer_rules(text).patterns
    homeless = [m or PKG for m in _modules(ROOT / PKG) if layer_of(patterns, m) is None]
    assert not homeless, f"modules in no layer of docs/architecture.md: {homeless}"


def test_imports_follow_the_layers(text: str) -> None:
    rules = layer_rules(text)
    seen_upward = set()
    broken = []
    for imp in core_imports():
        src, dst = layer_of(rules.patterns, imp.importer), layer_of(rules.patterns, imp.target)
        if src == dst or dst in rules.allowed.get(src or "", set()):
            continue
        pair = (imp.importer or PKG, imp.target or PKG)
        if pair in rules.upward:
            seen_upward.add(pair)
            continue
        broken.append(f"{imp.where}: {pair[0]} ({src}) imports {pair[1]} ({dst})")
    assert not broken, "imports against docs/architecture.md's layers:\n" + "\n".join(broken)
    stale = sorted(set(rules.upward) - seen_upward)
    assert not stale, f"docs/architecture.md lists upward imports that no longer happen: {stale}"


# --- the core knows no plugin ----------------------------------------------------------------


def test_the_core_imports_no_plugin_package() -> None:
    packages = plugin_packages()
    assert KNOWN_PLUGIN_PACKAGES <= packages, f"plugin packages not found: {sorted(KNOWN_PLUGIN_PACKAGES - packages)}"
    found = plugin_imports(ROOT / PKG, packages)
    assert not found, (
        "embodichain_core imports plugin packages (a plugin registers what the core looks up; docs/plugins.md):\n"
        + "\n".join(found)
    )


def test_the_plugin_import_check_sees_local_and_dynamic_imports(tmp_path: Path) -> None:
    pkg = tmp_path / "core"
    pkg.mkdir()
    (pkg / "mod.py").write_text(
        "from __future__ import annotations\n"
        "import importlib\n"
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from embodichain_viewer.session import ViewerSession\n"
        "import embodichain_functors.events\n"
        "def f():\n"
        "    from embodichain_viewer.session import open_session\n"
        "    return importlib.import_module('embodichain_lerobot.writer')\n"
        "from . import sibling\n"
        "import embodichain_functorsx\n"
    )
    found = plugin_imports(pkg, KNOWN_PLUGIN_PACKAGES)
    assert found == [
        "core/mod.py:6: embodichain_functors.events",
        "core/mod.py:8: embodichain_viewer.session",
        "core/mod.py:9: embodichain_lerobot.writer",
    ]
