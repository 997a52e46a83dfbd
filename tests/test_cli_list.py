"""The ``embodichain`` CLI: dispatch, help, unknown commands, ``list``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
from pathlib import Path
from typing import Any

import pytest

from embodichain_core.cli import list_cmd
from embodichain_core.cli.main import main
from embodichain_core.plugins import PluginLoadWarning, hookimpl
from embodichain_core.plugins.manager import isolated_plugins
from embodichain_core.testing import patch_entry_points
from embodichain_core.testing.pytest_plugin import plugin_manager, register_plugin  # noqa: F401

REPO = Path(__file__).resolve().parents[1]


class CatalogPlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register(
            "randomize_light",
            "json:dumps",
            kind="event",
            category="randomization.visual",
            description="Randomize lights",
        )
        register("joint_pos", "json:loads", kind="observation")

    @hookimpl
    def embodichain_register_tasks(self, register: Any) -> None:
        register("EcCliTask-v0", "ec_cli_tasks:Env", max_episode_steps=77, description="A test task")

    @hookimpl
    def embodichain_register_robots(self, register: Any) -> None:
        register("DexforceW1", "ec_robots.w1:DexforceW1Cfg")

    @hookimpl
    def embodichain_register_sensors(self, register: Any) -> None:
        register("StereoCamera", "ec_sensors:StereoCameraCfg", "ec_sensors:StereoCamera")

    @hookimpl
    def embodichain_register_assets(self, register: Any) -> None:
        register("ec-pack", "/data/ec-pack")


@pytest.fixture
def catalog(register_plugin: Any) -> str:  # noqa: F811
    return register_plugin(CatalogPlugin(), name="catalog")


def _list(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    assert main(["list", *args]) == 0
    return capsys.readouterr().out


def test_list_functors_table(catalog: str, capsys: pytest.CaptureFixture[str]) -> None:
    lines = _list(capsys, "functors").splitlines()
    assert lines[0].split() == ["NAME", "KIND", "CATEGORY", "PROVIDER", "DESCRIPTION"]
    row = next(line for line in lines if line.startswith("randomize_light"))
    assert row.split()[:4] == ["randomize_light", "event", "randomization.visual", "catalog"]
    assert row.endswith("Randomize lights")
    assert lines[0].index("KIND") == row.index("event")  # aligned


def test_list_other_kinds(catalog: str, capsys: pytest.CaptureFixture[str]) -> None:
    tasks = _list(capsys, "tasks")
    assert "EcCliTask-v0" in tasks
    assert "ec_cli_tasks:Env" in tasks
    assert " 77 " in tasks
    assert "ec_robots.w1:DexforceW1Cfg" in _list(capsys, "robots")
    assert "ec_sensors:StereoCamera " in _list(capsys, "sensors") + " "
    assert "/data/ec-pack" in _list(capsys, "assets")
    commands = _list(capsys, "commands")
    assert "run-env" in commands
    assert "embodichain_core.cli.run_env:main" in commands


def test_list_json_and_provider_filter(catalog: str, capsys: pytest.CaptureFixture[str]) -> None:
    rows = json.loads(_list(capsys, "functors", "--json", "--provider", "catalog"))
    assert [r["name"] for r in rows] == ["joint_pos", "randomize_light"]
    assert rows[1]["kind"] == "event"
    assert rows[1]["target"] == "json:dumps"
    assert json.loads(_list(capsys, "functors", "--json", "--provider", "nobody")) == []
    plugins = {r["name"]: r for r in json.loads(_list(capsys, "plugins", "--json"))}
    assert plugins["catalog"]["registered"]["tasks"] == ["EcCliTask-v0"]


def test_list_resolve_fills_descriptions(catalog: str, capsys: pytest.CaptureFixture[str]) -> None:
    rows = json.loads(_list(capsys, "functors", "--json", "--resolve"))
    assert rows[0]["name"] == "joint_pos"
    assert rows[0]["description"].startswith("Deserialize")


def test_list_plugins_shows_failures(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    def broken() -> Any:
        raise ImportError("no module named 'missing_dep'")

    ep = types.SimpleNamespace(name="broken-plugin", value="broken.plugin", dist=None, load=broken)
    patch_entry_points(monkeypatch, lambda installed: [ep])
    with pytest.warns(PluginLoadWarning), isolated_plugins(load_entry_points=True):
        out = _list(capsys, "plugins")
    assert "embodichain-core" in out
    assert "commands=5" in out
    assert "broken-plugin" in out
    assert "failed" in out
    assert "broken-plugin: ImportError: no module named 'missing_dep'" in out


def test_empty_listing(plugin_manager: Any, capsys: pytest.CaptureFixture[str]) -> None:  # noqa: F811
    assert _list(capsys, "robots").strip() == "no robots registered"


def test_unknown_command_suggests(plugin_manager: Any, capsys: pytest.CaptureFixture[str]) -> None:  # noqa: F811
    assert main(["lsit"]) == 2
    assert "unknown command 'lsit'. Did you mean 'list'?" in capsys.readouterr().err


def test_command_gets_argv_and_help(register_plugin: Any, monkeypatch: pytest.MonkeyPatch) -> None:  # noqa: F811
    seen: list[list[str]] = []

    def cmd(argv: list[str]) -> int:
        seen.append(argv)
        return 3

    module = types.ModuleType("ec_cli_cmd")
    module.cmd = cmd
    monkeypatch.setitem(sys.modules, "ec_cli_cmd", module)

    class CommandPlugin:
        @hookimpl
        def embodichain_register_commands(self, register: Any) -> None:
            register("hello", "ec_cli_cmd:cmd", help="Say hello")

    register_plugin(CommandPlugin())
    assert main(["hello", "--help", "x"]) == 3
    assert seen == [["--help", "x"]]
    assert main(["list", "--help"]) == 0  # reaches list's own parser (argparse exits 0)


def test_broken_command_target(register_plugin: Any, capsys: pytest.CaptureFixture[str]) -> None:  # noqa: F811
    class CommandPlugin:
        @hookimpl
        def embodichain_register_commands(self, register: Any) -> None:
            register("broken", "ec_no_such_cli_mod:main")

    register_plugin(CommandPlugin(), name="cmds")
    assert main(["broken"]) == 1
    assert "cannot load command 'broken' provided by 'cmds'" in capsys.readouterr().err


def _run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    code = (
        "import sys; from embodichain_core.cli.main import main; rc = main(sys.argv[1:]);"
        "mods = [m for m in sys.modules if m.startswith('embodichain_core.cli.') and m != 'embodichain_core.cli.main'];"
        "print('IMPORTED', mods); sys.exit(rc)"
    )
    env = {**os.environ, "EMBODICHAIN_BLOCK_PLUGINS": "*", "PYTHONPATH": str(REPO)}
    return subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True)


def test_help_and_version_import_no_command_module() -> None:
    result = _run_cli("--help")
    assert result.returncode == 0, result.stderr
    assert "run-env" in result.stdout
    assert "decompose" in result.stdout
    assert "IMPORTED []" in result.stdout
    version = _run_cli("--version")
    assert version.returncode == 0
    assert "embodichain-core " in version.stdout
    assert "IMPORTED []" in version.stdout


def test_list_cmd_main_directly(catalog: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert list_cmd.main(["tasks"]) == 0
    assert "EcCliTask-v0" in capsys.readouterr().out
