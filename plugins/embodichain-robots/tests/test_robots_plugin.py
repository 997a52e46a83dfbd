"""The plugin entry point: registrations, cheap import, ``embodichain list robots``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def test_plugin_registers_both_robots(register_plugin: object, plugin_manager: object) -> None:
    import embodichain_robots.plugin as plugin

    register_plugin(plugin)
    names = plugin_manager.registry("robots").names()
    assert {"DexforceW1", "SevenDofArm"} <= set(names)


def test_plugin_import_is_cheap() -> None:
    code = (
        "import sys, embodichain_robots, embodichain_robots.plugin; "
        "print(sorted(m for m in ('torch', 'mujoco') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_cli_lists_both_robots() -> None:
    exe = Path(sys.executable).with_name("embodichain")
    out = subprocess.run([str(exe), "list", "robots"], capture_output=True, text=True, check=True, timeout=120)
    assert "DexforceW1" in out.stdout
    assert "SevenDofArm" in out.stdout
    assert "embodichain-robots" in out.stdout
