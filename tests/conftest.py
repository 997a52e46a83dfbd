"""Core test fixtures; the helpers live in :mod:`core_testlib` (unique module name).

The test-only plugins under ``tests/fixture_plugins/`` are never installed into the
environment (``FixtureReach-v0`` must not show in a user's ``embodichain list tasks``).
The tests that need them request :func:`fixture_plugins`, which exposes them for the
duration of a test module exactly as an installation would: a directory holding a copy of
each plugin's packages and a generated ``*.dist-info`` with its ``embodichain`` entry
point goes onto ``sys.path`` (and onto ``PYTHONPATH``, for subprocesses), and the plugins
are loaded through their entry points into an isolated plugin manager.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import os
import re
import shutil
import sys
from pathlib import Path
from typing import Any, Iterator

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from core_testlib import make_cfg, make_env  # noqa: E402,F401  (fixtures)

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

#: Source directories of the test-only plugins (each has a pyproject.toml).
FIXTURE_PLUGINS_DIR = Path(__file__).resolve().parent / "fixture_plugins"


def _normalized(name: str) -> str:
    """A distribution name as a ``*.dist-info`` directory spells it (PEP 427)."""
    return re.sub(r"[-_.]+", "_", name).lower()


def _packages(source: Path) -> list[Path]:
    """The top-level packages of the plugin at ``source`` (build outputs left out)."""
    return sorted(
        p for p in source.iterdir() if p.is_dir() and (p / "__init__.py").is_file() and not p.name.endswith(".egg-info")
    )


def expose_plugin(source: Path, site: Path) -> str:
    """Make the plugin at ``source`` importable and discoverable from ``site``.

    Copies its packages into ``site`` and writes ``<name>-<version>.dist-info`` with its
    metadata and entry points, as ``pip install`` would, without touching the environment.

    Args:
        source: the plugin's directory (with ``pyproject.toml``).
        site: a directory that goes onto ``sys.path``.

    Returns:
        The plugin's distribution name.
    """
    project = tomllib.loads((source / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    name, version = project["name"], project["version"]
    packages = _packages(source)
    for package in packages:
        shutil.copytree(package, site / package.name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    info = site / f"{_normalized(name)}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\nSummary: {project.get('description', '')}\n",
        encoding="utf-8",
    )
    groups = project.get("entry-points", {})
    lines = [
        line
        for group, eps in groups.items()
        for line in (f"[{group}]", *(f"{ep} = {target}" for ep, target in eps.items()), "")
    ]
    (info / "entry_points.txt").write_text("\n".join(lines), encoding="utf-8")
    (info / "top_level.txt").write_text("".join(f"{p.name}\n" for p in packages), encoding="utf-8")
    (info / "INSTALLER").write_text("tests/conftest.py\n", encoding="utf-8")
    return name


def _installed(name: str) -> bool:
    try:
        importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


@pytest.fixture(scope="session")
def fixture_plugins_site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory exposing every plugin of ``tests/fixture_plugins/`` (not yet on ``sys.path``).

    A plugin already installed in the environment (by an older set-up) is not exposed
    twice; ``test_fixture_plugin.py`` reports it.
    """
    site = tmp_path_factory.mktemp("fixture_plugins_site")
    for source in sorted(FIXTURE_PLUGINS_DIR.glob("*/pyproject.toml")):
        project = tomllib.loads(source.read_text(encoding="utf-8"))["project"]
        if not _installed(project["name"]):
            expose_plugin(source.parent, site)
    return site


@pytest.fixture(scope="module")
def fixture_plugins(fixture_plugins_site: Path) -> Iterator[Any]:
    """The test-only plugins, loaded through their entry points, for one test module.

    ``sys.path`` and ``PYTHONPATH`` get :func:`fixture_plugins_site` (subprocesses see the
    plugins too); the installed plugins and the fixture plugins are loaded into an
    isolated plugin manager (``embodichain_core.testing``'s ``isolated_plugins``). Everything
    is restored afterwards: the global plugin state, gymnasium's ids, ``sys.path``,
    ``PYTHONPATH`` and the imported fixture modules.

    Yields:
        The plugin manager.
    """
    from embodichain_core.plugins.manager import isolated_plugins

    site = str(fixture_plugins_site)
    saved_path, saved_env = list(sys.path), os.environ.get("PYTHONPATH")
    modules = {p.name for p in fixture_plugins_site.iterdir() if p.is_dir() and not p.name.endswith(".dist-info")}
    sys.path.insert(0, site)
    os.environ["PYTHONPATH"] = os.pathsep.join([site, *([saved_env] if saved_env else [])])
    importlib.invalidate_caches()
    try:
        with isolated_plugins(load_entry_points=True) as pm:
            yield pm
    finally:
        sys.path[:] = saved_path
        if saved_env is None:
            os.environ.pop("PYTHONPATH", None)
        else:
            os.environ["PYTHONPATH"] = saved_env
        for module in [m for m in sys.modules if m.split(".")[0] in modules]:
            del sys.modules[module]
        importlib.invalidate_caches()
