"""The plugin host: loading, failures, blocking, hook checks, gymnasium tasks."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import types
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import pluggy
import pytest

from embodichain_core.plugins import (
    CORE_PLUGIN_NAME,
    AmbiguousNameError,
    NameClashWarning,
    PluginLoadWarning,
    failed_plugins,
    get_asset_root,
    get_plugin_manager,
    get_sensor_classes,
    hookimpl,
    is_visual_randomization,
    isolated_plugins,
    list_plugins,
    load_plugins,
    register_plugin,
    unregister_plugin,
)
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.testing import patch_entry_points
from embodichain_core.testing.pytest_plugin import plugin_manager  # noqa: F401  (fixture)

REPO = Path(__file__).resolve().parents[1]


@dataclass
class FakeEntryPoint:
    """Stands in for ``importlib.metadata.EntryPoint``."""

    name: str
    loader: Callable[[], Any]
    value: str = "fake.module"
    dist: Any = field(default_factory=lambda: types.SimpleNamespace(version="1.2.3"))
    loaded: int = 0

    def load(self) -> Any:
        self.loaded += 1
        return self.loader()


class FunctorPlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register("randomize_light", "json:dumps", kind="event", category="randomization.visual")
        register("joint_pos", "json:loads", kind="observation")


class OtherFunctorPlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register("reach_reward", "json:dumps", kind="reward")
        register("randomize_light", "json:loads", kind="event")


class RaisingPlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register("partial", "json:dumps", kind="event")
        raise RuntimeError("boom in hook")


class MisspelledPlugin:
    @hookimpl
    def embodichain_register_functor(self, register: Any) -> None:  # missing "s"
        pass


class WrongArgumentPlugin:
    @hookimpl
    def embodichain_register_robots(self, reg: Any) -> None:  # the argument must be "register"
        pass


class TaskPlugin:
    @hookimpl
    def embodichain_register_tasks(self, register: Any) -> None:
        register("EcTestTask-v0", "ec_test_tasks:TestEnv", max_episode_steps=123, kwargs={"a": 1})
        register("EcTestTaskNoLimit-v0", "ec_test_tasks:TestEnv")


def _fail_import() -> Any:
    raise ImportError("cannot import name 'thing' from 'bad_plugin'")


def _entry_points(monkeypatch: pytest.MonkeyPatch, *eps: FakeEntryPoint) -> None:
    patch_entry_points(monkeypatch, lambda installed: list(eps))


def _load_with(monkeypatch: pytest.MonkeyPatch, *eps: FakeEntryPoint) -> Any:
    _entry_points(monkeypatch, *eps)
    return isolated_plugins(load_entry_points=True)


def test_builtins_and_idempotent_load(plugin_manager: Any) -> None:  # noqa: F811
    assert load_plugins() is plugin_manager is get_plugin_manager()
    commands = plugin_manager.registry("commands")
    assert {"list", "run-env", "decompose", "new", "bench"} <= set(commands.names())
    assert commands.entry("list").provider == CORE_PLUGIN_NAME
    assert commands.entry("run-env").lazy
    assert not commands.entry("run-env").resolved
    demo = plugin_manager.registry("tasks").entry("EmbodiChainDemo-v0")  # the demo task: the core's tasks hook
    assert (demo.provider, demo.target, demo.resolved) == (
        CORE_PLUGIN_NAME,
        "embodichain_core.demo:DemoSceneEnv",
        False,
    )
    assert Path(demo.meta["config"]).name == "demo_scene.json"
    assert [i.name for i in list_plugins()] == [CORE_PLUGIN_NAME]
    plugin_manager.check_pending()


def test_failing_plugin_reported_others_load(monkeypatch: pytest.MonkeyPatch) -> None:
    good = FakeEntryPoint("good-plugin", FunctorPlugin)
    bad = FakeEntryPoint("bad-plugin", _fail_import)
    with pytest.warns(PluginLoadWarning, match="'bad-plugin'") as record:
        with _load_with(monkeypatch, bad, good) as pm:
            assert pm.registry("functors").names() == ["joint_pos", "randomize_light"]
            ((name, tb),) = failed_plugins()
            infos = {i.name: i for i in list_plugins()}
    assert name == "bad-plugin"
    assert "Traceback" in tb
    assert "cannot import name 'thing'" in tb
    assert infos["bad-plugin"].status == "failed"
    assert infos["bad-plugin"].error_summary.startswith("ImportError: cannot import name")
    assert infos["good-plugin"].status == "loaded"
    assert infos["good-plugin"].version == "1.2.3"
    assert infos["good-plugin"].registered == {"functors": ["randomize_light", "joint_pos"]}
    # one line on every command, naming the error and where the traceback is
    message = str(record[0].message)
    assert "\n" not in message
    assert "Traceback" not in message
    assert "ImportError: cannot import name 'thing'" in message
    assert "embodichain list plugins -v" in message


def test_raising_hook_rolls_back_and_others_load(monkeypatch: pytest.MonkeyPatch) -> None:
    eps = FakeEntryPoint("raising", RaisingPlugin), FakeEntryPoint("good", FunctorPlugin)
    with pytest.warns(PluginLoadWarning, match="'raising'(.|\n)*boom in hook"):
        with _load_with(monkeypatch, *eps) as pm:
            assert "partial" not in pm.registry("functors")
            assert "joint_pos" in pm.registry("functors")
            assert pm.get_plugin("raising") is None


@pytest.mark.parametrize("reverse", [False, True])
def test_clash_across_plugins_keeps_both(monkeypatch: pytest.MonkeyPatch, reverse: bool) -> None:
    eps = [FakeEntryPoint("plugin-a", FunctorPlugin), FakeEntryPoint("plugin-b", OtherFunctorPlugin)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clash is no load failure
        with _load_with(monkeypatch, *(eps[::-1] if reverse else eps)) as pm:
            functors = pm.registry("functors")
            assert {i.name: i.status for i in list_plugins()} == {
                CORE_PLUGIN_NAME: "loaded",
                "plugin-a": "loaded",
                "plugin-b": "loaded",
            }
            assert functors.get("plugin-a/randomize_light") is json.dumps
            assert functors.get("plugin-b/randomize_light") is json.loads
            assert functors.get("reach_reward") is json.dumps
            assert functors.get("joint_pos") is json.loads
            with pytest.raises(AmbiguousNameError, match="'plugin-a' and 'plugin-b'"):
                functors.get("randomize_light")
            assert [str(c) for c in pm.name_clashes()] == [
                "functor 'randomize_light' is provided by 'plugin-a' and 'plugin-b' "
                "(use 'plugin-a/randomize_light' or 'plugin-b/randomize_light')"
            ]
            assert not is_visual_randomization("randomize_light")  # ambiguous: decided at resolution


def test_plugins_are_named_after_their_distribution_and_load_sorted(monkeypatch: pytest.MonkeyPatch) -> None:
    def dist(name: str) -> Any:
        return types.SimpleNamespace(name=name, version="2.0")

    eps = [
        FakeEntryPoint("zeta", FunctorPlugin, dist=dist("Zeta_Plugin")),
        FakeEntryPoint("alpha-main", OtherFunctorPlugin, dist=dist("Alpha.Plugin")),
        FakeEntryPoint("alpha-plugin", TaskPlugin, dist=dist("Alpha.Plugin")),
    ]
    with _load_with(monkeypatch, *eps) as pm:
        infos = list_plugins()
        assert [(i.name, i.entry_point) for i in infos] == [
            (CORE_PLUGIN_NAME, ""),
            ("alpha-plugin", "alpha-plugin"),
            ("alpha-plugin.alpha-main", "alpha-main"),
            ("zeta-plugin", "zeta"),
        ]
        assert pm.registry("functors").get("zeta-plugin/joint_pos") is json.loads
        assert "alpha-plugin/EcTestTask-v0" in pm.registry("tasks")


def test_block_env_var(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("EMBODICHAIN_BLOCK_PLUGINS", "other, blocked-plugin")
    blocked = FakeEntryPoint("blocked-plugin", FunctorPlugin)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with _load_with(monkeypatch, blocked) as pm:
            assert blocked.loaded == 0
            assert len(pm.registry("functors")) == 0
            assert {i.name: i.status for i in list_plugins()}["blocked-plugin"] == "blocked"


def test_misspelled_hook_entry_point(monkeypatch: pytest.MonkeyPatch) -> None:
    eps = FakeEntryPoint("typo-plugin", MisspelledPlugin), FakeEntryPoint("good", FunctorPlugin)
    with pytest.warns(PluginLoadWarning, match="plugin 'typo-plugin' implements unknown hook") as rec:
        with _load_with(monkeypatch, *eps) as pm:
            pm.check_pending()  # the bad plugin was removed
            assert "joint_pos" in pm.registry("functors")
    assert "Did you mean 'embodichain_register_" in str(rec[0].message)


def test_wrong_hook_argument_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    eps = FakeEntryPoint("bad-args", WrongArgumentPlugin), FakeEntryPoint("good", FunctorPlugin)
    with pytest.warns(PluginLoadWarning, match="'bad-args'(.|\n)*PluginValidationError"):
        with _load_with(monkeypatch, *eps) as pm:
            assert "joint_pos" in pm.registry("functors")
            assert [name for name, _ in failed_plugins()] == ["bad-args"]


def test_misspelled_hook_runtime_raises(plugin_manager: Any) -> None:  # noqa: F811
    with pytest.raises(pluggy.PluginValidationError, match="'typo' implements unknown hook"):
        register_plugin(MisspelledPlugin(), name="typo")
    assert plugin_manager.get_plugin("typo") is None


def test_register_and_unregister_plugin(plugin_manager: Any) -> None:  # noqa: F811
    name = register_plugin(FunctorPlugin())
    assert name.endswith("FunctorPlugin")
    entry = plugin_manager.registry("functors").entry("randomize_light")
    assert entry.provider == name
    assert is_visual_randomization("randomize_light")
    assert not is_visual_randomization("joint_pos")
    assert not is_visual_randomization("nope")
    unregister_plugin(name)
    assert len(plugin_manager.registry("functors")) == 0


def test_module_plugin_and_helpers(plugin_manager: Any, tmp_path: Path) -> None:  # noqa: F811
    module = types.ModuleType("ec_test_module_plugin")
    calls: list[int] = []

    @hookimpl
    def embodichain_register_sensors(register: Any) -> None:
        register("Camera", "json:JSONDecoder", "json:JSONEncoder")

    @hookimpl
    def embodichain_register_assets(register: Any) -> None:
        register("pack", lambda: calls.append(1) or tmp_path)

    def embodichain_register_robots(register: Any) -> None:  # not marked @hookimpl: not a hook
        raise AssertionError("an unmarked function was called as a hook")

    module.embodichain_register_sensors = embodichain_register_sensors
    module.embodichain_register_assets = embodichain_register_assets
    module.embodichain_register_robots = embodichain_register_robots
    assert register_plugin(module) == "ec_test_module_plugin"
    import json

    assert get_sensor_classes("camera") == (json.JSONDecoder, json.JSONEncoder)
    assert get_asset_root("pack") == tmp_path == get_asset_root("pack")
    assert calls == [1]


def test_tasks_reach_gymnasium_without_time_limit(plugin_manager: Any) -> None:  # noqa: F811
    import gymnasium

    register_plugin(TaskPlugin(), name="tasks-plugin")
    spec = gymnasium.registry["EcTestTask-v0"]
    assert spec.entry_point == "ec_test_tasks:TestEnv"
    assert spec.max_episode_steps is None
    assert spec.kwargs == {"a": 1}  # the episode limit is the registry's, read by the env
    assert spec.disable_env_checker
    assert not spec.order_enforce
    assert gymnasium.registry["EcTestTaskNoLimit-v0"].kwargs == {}
    entry = plugin_manager.registry("tasks").entry("EcTestTask-v0")
    assert entry.meta["max_episode_steps"] == 123
    assert entry.provider == "tasks-plugin"


def test_isolation_removes_gym_ids_and_restores_state() -> None:
    import gymnasium

    outer = get_plugin_manager()
    with isolated_plugins() as pm:
        assert pm is not outer
        register_plugin(TaskPlugin())
        assert "EcTestTask-v0" in gymnasium.registry
    assert "EcTestTask-v0" not in gymnasium.registry
    assert get_plugin_manager() is outer


def test_nested_isolation_shadows_and_restores_the_outer_gym_ids() -> None:
    import gymnasium

    class OtherTaskPlugin:
        @hookimpl
        def embodichain_register_tasks(self, register: Any) -> None:
            register("EcTestTask-v0", "other_pkg:OtherEnv")

    with isolated_plugins():
        register_plugin(TaskPlugin(), name="outer")
        outer_spec = gymnasium.registry["EcTestTask-v0"]
        with isolated_plugins():
            assert gymnasium.registry["EcTestTask-v0"] is outer_spec  # visible until shadowed
            register_plugin(OtherTaskPlugin(), name="inner")
            assert gymnasium.registry["EcTestTask-v0"].entry_point == "other_pkg:OtherEnv"
        assert gymnasium.registry["EcTestTask-v0"] is outer_spec
        assert "inner/EcTestTask-v0" not in gymnasium.registry
        assert "outer/EcTestTask-v0" in gymnasium.registry
    assert "EcTestTask-v0" not in gymnasium.registry


def test_gym_id_from_outside_the_plugins_is_left_alone(plugin_manager: Any) -> None:  # noqa: F811
    import gymnasium

    gymnasium.register("EcTestTask-v0", entry_point="ec_test_tasks:TestEnv")
    try:
        register_plugin(TaskPlugin(), name="tasks-plugin")  # same entry point: kept as is
        assert gymnasium.registry["EcTestTask-v0"].order_enforce  # untouched
        unregister_plugin("tasks-plugin")
        assert "EcTestTask-v0" in gymnasium.registry  # not ours to remove

        class Clash:
            @hookimpl
            def embodichain_register_tasks(self, register: Any) -> None:
                register("EcTestTask-v0", "other_pkg:OtherEnv")

        with pytest.warns(
            NameClashWarning,
            match="'EcTestTask-v0' is already registered outside(.|\n)*"
            "'ec_test_tasks:TestEnv'(.|\n)*'clash/EcTestTask-v0'",
        ):
            register_plugin(Clash(), name="clash")  # the plugin still loads, under its namespace
        assert gymnasium.registry["EcTestTask-v0"].entry_point == "ec_test_tasks:TestEnv"
        assert gymnasium.registry["clash/EcTestTask-v0"].entry_point == "other_pkg:OtherEnv"
    finally:
        gymnasium.registry.pop("EcTestTask-v0", None)


def test_trace_env_var(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("EMBODICHAIN_TRACE_PLUGINS", "1")
    with isolated_plugins():
        register_plugin(FunctorPlugin(), name="traced")
    assert "embodichain_register_functors" in capsys.readouterr().err


def test_plugin_modules_import_cheaply() -> None:
    # gymnasium is imported: the core's demo task is written into its registry at load
    code = (
        "import sys, embodichain_core.plugins, embodichain_core.cli.main, embodichain_core.testing;"
        "embodichain_core.plugins.load_plugins();"
        "heavy = [m for m in ('torch', 'mujoco', 'embodichain_core.demo', 'embodichain_core.envs') if m in sys.modules];"
        "assert not heavy, heavy"
    )
    env = {**os.environ, "EMBODICHAIN_BLOCK_PLUGINS": "*", "PYTHONPATH": str(REPO)}
    result = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


class ShimFirst(EmbodiedEnv):
    """A module-level env class: gymnasium imports tasks by ``"module:Class"``."""


class ShimSecond(EmbodiedEnv):
    pass


def test_register_env_runs_the_tasks_hook(plugin_manager: Any) -> None:  # noqa: F811
    import gymnasium

    from embodichain_core.envs import register_env
    from embodichain_core.envs.env_build import task_episode_limit
    from embodichain_core.plugins.registry import DuplicateRegistrationError

    register_env("EcShimTask-v0", max_episode_steps=7)(ShimFirst)
    entry = plugin_manager.registry("tasks").entry("EcShimTask-v0")
    assert entry.provider == ShimFirst.__module__  # the module is the provider, as a plugin would be
    assert entry.target is ShimFirst  # the class itself: its module need not be importable by name
    assert entry.target_repr == f"{ShimFirst.__module__}:ShimFirst"
    assert gymnasium.registry["EcShimTask-v0"].entry_point == entry.target
    assert gymnasium.registry["EcShimTask-v0"].kwargs == {}  # no hidden keyword: the limit is the registry's
    assert task_episode_limit(ShimFirst) == 7
    assert task_episode_limit(ShimSecond) is None
    with pytest.raises(DuplicateRegistrationError, match="registered twice .*ShimFirst.*override=True to replace it"):
        register_env("EcShimTask-v0")(ShimSecond)
    assert plugin_manager.registry("tasks").entry("EcShimTask-v0").target is ShimFirst
    register_env("EcShimTask-v0", override=True)(ShimSecond)
    assert gymnasium.registry["EcShimTask-v0"].entry_point is ShimSecond
    assert task_episode_limit(ShimFirst) is None

    class Local(EmbodiedEnv):
        pass

    with pytest.raises(TypeError, match="defined inside a function"):
        register_env("EcShimLocal-v0")(Local)


def test_register_env_leaves_a_gym_id_from_outside_the_plugins(plugin_manager: Any) -> None:  # noqa: F811
    import gymnasium

    from embodichain_core.envs import register_env

    gymnasium.register("EcShimForeign-v0", entry_point="other_pkg:OtherEnv")
    try:
        with pytest.warns(NameClashWarning, match="'EcShimForeign-v0' is already registered outside"):
            register_env("EcShimForeign-v0", override=True)(ShimFirst)
        assert gymnasium.registry["EcShimForeign-v0"].entry_point == "other_pkg:OtherEnv"  # not ours to replace
        tasks = plugin_manager.registry("tasks")
        qualified = tasks.qualified_name(tasks.entry("EcShimForeign-v0"))  # under its provider's namespace
        assert qualified.endswith("test_plugins/EcShimForeign-v0")
        assert gymnasium.registry[qualified].entry_point is ShimFirst
    finally:
        gymnasium.registry.pop("EcShimForeign-v0", None)
