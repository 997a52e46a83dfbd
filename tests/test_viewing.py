"""Which viewer ``headless: false`` opens (``sim_cfg.viewer`` / ``--viewer``), the headless
path importing nothing of the viewers, and the message when the viewer plugin is missing."""

from __future__ import annotations

import argparse
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_core.gym_utils import add_env_launcher_args_to_parser, launcher_overrides
from embodichain_core.viewing import INSTALL_HINT, attach_viewer, has_display, resolve_viewer_mode


@pytest.mark.parametrize(
    ("mode", "environ", "expected"),
    [
        ("auto", {"DISPLAY": ":0"}, "native"),
        ("auto", {"WAYLAND_DISPLAY": "wayland-0"}, "native"),
        ("auto", {}, "browser"),
        ("auto", {"DISPLAY": ""}, "browser"),
        ("browser", {"DISPLAY": ":0"}, "browser"),
        ("native", {"DISPLAY": ":1"}, "native"),
        ("none", {"DISPLAY": ":0"}, "none"),
    ],
)
def test_auto_picks_native_with_a_display_else_the_browser(mode: str, environ: dict, expected: str) -> None:
    assert resolve_viewer_mode(mode, environ) == expected


def test_native_without_a_display_is_one_error_suggesting_the_browser() -> None:
    with pytest.raises(ConfigError, match="--viewer browser") as err:
        resolve_viewer_mode("native", {})
    assert err.value.path == "sim_cfg.viewer"
    assert not has_display({})


def test_unknown_viewer_names_the_closest_mode() -> None:
    with pytest.raises(ConfigError, match="Did you mean 'browser'"):
        resolve_viewer_mode("browsr", {})


def _parse(*argv: str) -> dict:
    parser = argparse.ArgumentParser()
    add_env_launcher_args_to_parser(parser)
    return launcher_overrides(parser.parse_args(list(argv)))


def test_viewer_flag_turns_headless_off_and_none_leaves_it() -> None:
    assert _parse("--viewer", "browser") == {"viewer": "browser", "headless": False}
    assert _parse("--viewer", "none") == {"viewer": "none"}
    assert _parse() == {}
    assert _parse("--headless") == {"headless": True}
    with pytest.raises(ConfigError, match="drop --headless"):
        _parse("--headless", "--viewer", "native")


def _env(headless: bool, viewer: str = "browser") -> SimpleNamespace:
    return SimpleNamespace(cfg=SimpleNamespace(sim_cfg=SimpleNamespace(headless=headless, viewer=viewer)))


def test_headless_and_viewer_none_open_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "embodichain_viewer.session", None)  # importing it would fail
    assert attach_viewer(_env(True)) is None
    assert attach_viewer(_env(False, "none")) is None


def test_missing_viewer_plugin_is_one_message_with_the_install_command(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "embodichain_viewer.session", None)
    with pytest.raises(ConfigError, match="embodichain-viewer plugin") as err:
        attach_viewer(_env(False, "browser"))
    assert INSTALL_HINT in str(err.value)
    assert "--headless" in str(err.value)


def test_a_headless_run_imports_nothing_for_viewing() -> None:
    script = textwrap.dedent(
        """
        import sys
        from embodichain_core.cli.run_env import main
        assert main(["--headless", "--max_episodes", "1", "--max_steps", "3", "--quiet"]) == 0
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("embodichain_viewer", "viser", "mjviser", "glfw")
                        or m == "mujoco.viewer")
        print("LOADED", loaded)
        """
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "LOADED []" in out.stdout


def test_force_viewer_opens_one_for_envs_built_inside_the_block(monkeypatch: pytest.MonkeyPatch) -> None:
    from embodichain_core.viewing import force_viewer

    monkeypatch.setitem(sys.modules, "embodichain_viewer.session", None)  # an attempt to open one raises
    with force_viewer("browser"), pytest.raises(ConfigError, match="embodichain-viewer plugin"):
        attach_viewer(_env(True, "none"))
    with force_viewer("none"):
        assert attach_viewer(_env(False, "browser")) is None
    with force_viewer(None):
        assert attach_viewer(_env(True)) is None
    assert attach_viewer(_env(True)) is None  # the block ended
    with pytest.raises(ConfigError, match="unknown viewer"), force_viewer("window"):
        pass
