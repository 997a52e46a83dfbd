"""Which viewer ``headless: false`` opens (``sim_cfg.viewer`` / ``--viewer``), the headless
path importing nothing of the viewers, and the viewers looked up in the plugins' registry:
fixture viewer plugins registered here, never an installed one."""

from __future__ import annotations

import argparse
import subprocess
import sys
import textwrap
from types import SimpleNamespace
from typing import Any, Iterator

import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_core.gym_utils import add_env_launcher_args_to_parser, launcher_overrides
from embodichain_core.plugins import ViewerRegister, hookimpl, isolated_plugins, register_plugin
from embodichain_core.viewing import INSTALL_ADVICE, attach_viewer, force_viewer, has_display, resolve_viewer_mode


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


def _env(headless: bool, viewer: str = "browser", port: int = 8080) -> SimpleNamespace:
    sim_cfg = SimpleNamespace(headless=headless, viewer=viewer, viewer_port=port)
    return SimpleNamespace(cfg=SimpleNamespace(sim_cfg=sim_cfg))


class FixtureViewers:
    """Registers an opener for each of ``names`` that records its calls."""

    def __init__(self, *names: str, opener: Any = None):
        self.names, self.calls = names, []
        self.opener = opener or self.open

    def open(self, env: Any, mode: str, port: int = 8080) -> tuple[str, int]:
        self.calls.append((env, mode, port))
        return ("session", port)

    @hookimpl
    def embodichain_register_viewers(self, register: ViewerRegister) -> None:
        for name in self.names:
            register(name, self.opener, description=f"fixture {name}")


@pytest.fixture
def no_viewers() -> Iterator[None]:
    with isolated_plugins():  # the core's built-ins only: no plugin registers a viewer
        yield


def test_headless_and_viewer_none_open_nothing(no_viewers: None) -> None:
    assert attach_viewer(_env(True)) is None
    assert attach_viewer(_env(False, "none")) is None


def test_the_registered_opener_gets_the_env_the_mode_and_the_port(no_viewers: None) -> None:
    viewers = FixtureViewers("native", "browser")
    register_plugin(viewers, name="fixture-viewers")
    env = _env(False, "browser", port=9123)
    assert attach_viewer(env) == ("session", 9123)
    assert viewers.calls == [(env, "browser", 9123)]


def test_no_viewer_plugin_is_one_message_naming_what_to_install(no_viewers: None) -> None:
    with pytest.raises(ConfigError, match="opens the browser viewer, but no installed plugin registers it") as err:
        attach_viewer(_env(False, "browser"))
    assert err.value.path == "sim_cfg.headless"
    assert "no viewers are registered" in str(err.value)
    assert INSTALL_ADVICE in str(err.value)
    assert "embodichain_register_viewers" in str(err.value)
    assert "--headless" in str(err.value)


def test_a_missing_viewer_names_the_registered_ones(no_viewers: None) -> None:
    register_plugin(FixtureViewers("native"), name="fixture-viewers")
    with pytest.raises(ConfigError, match="the viewers registered are 'native \\(fixture-viewers\\)'"):
        attach_viewer(_env(False, "browser"))


def test_two_plugins_registering_one_viewer_are_named(no_viewers: None) -> None:
    register_plugin(FixtureViewers("browser"), name="viewers-a")
    register_plugin(FixtureViewers("browser"), name="viewers-b")
    with pytest.raises(ConfigError, match="several plugins register it \\('viewers-a' and 'viewers-b'\\)"):
        attach_viewer(_env(False, "browser"))


def test_an_opener_that_fails_to_import_names_the_plugin(no_viewers: None) -> None:
    register_plugin(FixtureViewers("browser", opener="embodichain_no_such_viewer.session:open"), name="broken")
    with pytest.raises(ConfigError, match="cannot load viewer 'browser' provided by 'broken'") as err:
        attach_viewer(_env(False, "browser"))
    assert "No module named 'embodichain_no_such_viewer'" in str(err.value)


def test_a_viewer_is_registered_under_a_known_name(no_viewers: None) -> None:
    with pytest.raises(ValueError, match="viewer 'browsr' from 'typo'.*Did you mean 'browser'"):
        register_plugin(FixtureViewers("browsr"), name="typo")
    with pytest.raises(TypeError, match="the opener must be a 'module:function' string or a callable"):
        register_plugin(FixtureViewers("native", opener=42), name="not-callable")


def test_a_headless_run_imports_nothing_for_viewing() -> None:
    """Only the plugin's registration module may load (it names its opener as a string)."""
    script = textwrap.dedent(
        """
        import sys
        from embodichain_core.cli.run_env import main
        assert main(["--headless", "--max_episodes", "1", "--max_steps", "3", "--quiet"]) == 0
        registration = ("embodichain_viewer", "embodichain_viewer.plugin")
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("embodichain_viewer", "viser", "mjviser", "glfw")
                        and m not in registration or m == "mujoco.viewer")
        print("LOADED", loaded)
        """
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "LOADED []" in out.stdout


def test_force_viewer_opens_one_for_envs_built_inside_the_block(no_viewers: None) -> None:
    viewers = FixtureViewers("browser")
    register_plugin(viewers, name="fixture-viewers")
    with force_viewer("browser"):
        assert attach_viewer(_env(True, "none")) == ("session", 8080)
    with force_viewer("none"):
        assert attach_viewer(_env(False, "browser")) is None
    with force_viewer(None):
        assert attach_viewer(_env(True)) is None
    assert attach_viewer(_env(True)) is None  # the block ended
    assert len(viewers.calls) == 1
    with pytest.raises(ConfigError, match="unknown viewer"), force_viewer("window"):
        pass
