"""Name clashes between plugins installed through REAL entry points.

Two fixture distributions, ``ecclash-alpha`` and ``ecclash-beta``, are written as
``*.dist-info`` folders (METADATA + entry_points.txt) next to their plugin modules in
temporary directories put on ``sys.path``, so ``importlib.metadata`` discovers them like
installed packages. Both register the functor ``shared_event``, the task
``ClashTask-v0``, the robot ``ClashArm``, the sensor ``ClashCam``, the command ``hello``
and the data root ``data``; each also has names of its own. Every check runs with both
``sys.path`` orders (so both discovery orders).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import json
import sys
import warnings
from pathlib import Path
from typing import Any, Iterator

import gymnasium as gym
import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_core.plugins import (
    AmbiguousNameError,
    get_registry,
    isolated_plugins,
    list_plugins,
    unregister_plugin,
)
from embodichain_core.testing import patch_entry_points

DISTS = ("alpha", "beta")
ORDERS = [DISTS, DISTS[::-1]]

PLUGIN_SOURCE = '''
"""Fixture plugin @NAME@ (written by tests/test_plugin_clashes.py)."""
import os

import gymnasium
import gymnasium.vector

from embodichain_core.plugins import hookimpl
from embodichain_core.sim.cfg import RobotCfg, SensorCfg
from embodichain_core.utils.configclass import configclass

WHO = "@NAME@"
DATA = os.path.join(os.path.dirname(__file__), "data")


def shared_event(env, env_ids):
    """@NAME@'s shared_event."""


def @NAME@_only(env, env_ids):
    """Only in @NAME@."""


class ClashEnv(gymnasium.Env):
    metadata = {"render_modes": [], "autoreset_mode": gymnasium.vector.AutoresetMode.SAME_STEP}

    def __init__(self, who="?", **kwargs):
        self.who, self.kwargs = who, kwargs


@configclass
class ArmCfg(RobotCfg):
    pass


@configclass
class CamCfg(SensorCfg):
    pass


class Cam:
    pass


def hello(argv):
    print("hello from @NAME@", argv)
    return 0


@hookimpl
def embodichain_register_functors(register):
    register("shared_event", "ecclash_@NAME@:shared_event", kind="event")
    register("@NAME@_only", "ecclash_@NAME@:@NAME@_only", kind="event")


@hookimpl
def embodichain_register_tasks(register):
    register("ClashTask-v0", "ecclash_@NAME@:ClashEnv", kwargs={"who": WHO})
    register("@NAME@Only-v0", "ecclash_@NAME@:ClashEnv", kwargs={"who": WHO})


@hookimpl
def embodichain_register_robots(register):
    register("ClashArm", "ecclash_@NAME@:ArmCfg")


@hookimpl
def embodichain_register_sensors(register):
    register("ClashCam", "ecclash_@NAME@:CamCfg", "ecclash_@NAME@:Cam")


@hookimpl
def embodichain_register_commands(register):
    register("hello", "ecclash_@NAME@:hello", help="Say hello from @NAME@")


@hookimpl
def embodichain_register_assets(register):
    register("data", DATA)
'''


def write_dist(root: Path, dist: str, module: str, source: str, entry_point: str | None = None) -> Path:
    """Write ``<module>/`` and ``<module>-1.0.dist-info`` under ``root``; return ``root``."""
    package = root / module
    (package / "data").mkdir(parents=True)
    (package / "__init__.py").write_text(source)
    (package / "data" / f"{module}.txt").write_text(module)
    (package / "data" / "shared.txt").write_text(module)
    info = root / f"{module}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[embodichain]\n{entry_point or dist} = {module}\n")
    return root


@pytest.fixture
def dist_roots(tmp_path: Path) -> dict[str, Path]:
    """One folder per fixture distribution (not yet on sys.path)."""
    return {
        name: write_dist(tmp_path / name, f"ecclash-{name}", f"ecclash_{name}", PLUGIN_SOURCE.replace("@NAME@", name))
        for name in DISTS
    }


@pytest.fixture(autouse=True)
def clean_state(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """No blocked plugins from the caller's environment; fixture modules forgotten afterwards."""
    monkeypatch.delenv("EMBODICHAIN_BLOCK_PLUGINS", raising=False)
    yield
    for name in [m for m in sys.modules if m.startswith("ecclash_")]:
        del sys.modules[name]


def only_fixture_entry_points(monkeypatch: pytest.MonkeyPatch) -> None:
    """Real ``importlib.metadata`` discovery, restricted to the fixture distributions
    (core tests use no installed plugin)."""
    patch_entry_points(monkeypatch, lambda installed: [ep for ep in installed if ep.dist.name.startswith("ecclash")])


def install(monkeypatch: pytest.MonkeyPatch, roots: dict[str, Path], order: tuple[str, ...]) -> list[str]:
    """Put the fixture folders on sys.path, first of ``order`` first; return the discovery order."""
    for name in reversed(order):
        monkeypatch.syspath_prepend(str(roots[name]))
    only_fixture_entry_points(monkeypatch)
    return [ep.dist.name for ep in importlib.metadata.entry_points(group="embodichain")]


@pytest.mark.parametrize("order", ORDERS, ids=["alpha-first", "beta-first"])
def test_both_plugins_load_and_qualified_names_resolve(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], order: tuple[str, ...]
) -> None:
    discovered = install(monkeypatch, dist_roots, order)
    assert discovered == [f"ecclash-{name}" for name in order]  # both discovery orders are exercised
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clash is neither a load failure nor a warning
        with isolated_plugins(load_entry_points=True) as pm:
            assert {i.name: i.status for i in list_plugins()} == {
                "embodichain-core": "loaded",
                "ecclash-alpha": "loaded",
                "ecclash-beta": "loaded",
            }
            alpha, beta = sys.modules["ecclash_alpha"], sys.modules["ecclash_beta"]
            functors = pm.registry("functors")
            assert functors.get("ecclash-alpha/shared_event") is alpha.shared_event
            assert functors.get("ecclash-beta/shared_event") is beta.shared_event
            assert functors.get("alpha_only") is alpha.alpha_only
            assert functors.get("beta_only") is beta.beta_only
            assert get_registry("robots").get("ecclash-beta/ClashArmCfg") is beta.ArmCfg
            assert get_registry("sensors").get("ecclash-alpha/clashcam") is alpha.CamCfg
            assert get_registry("commands").get("ecclash-beta/hello") is beta.hello
            assert gym.make("ecclash-alpha/ClashTask-v0").unwrapped.who == "alpha"
            assert type(gym.make("ecclash-beta/ClashTask-v0").unwrapped) is beta.ClashEnv
            assert gym.make("betaOnly-v0").unwrapped.who == "beta"  # a unique bare id


@pytest.mark.parametrize("order", ORDERS, ids=["alpha-first", "beta-first"])
def test_ambiguous_bare_names_raise_one_error_naming_both(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], order: tuple[str, ...]
) -> None:
    from embodichain_core.managers.manager_base import resolve_func
    from embodichain_core.sim.cfg import RobotCfg, SensorCfg

    install(monkeypatch, dist_roots, order)
    with isolated_plugins(load_entry_points=True) as pm:
        with pytest.raises(AmbiguousNameError) as info:
            pm.registry("functors").get("shared_event")
        assert str(info.value) == (
            "functor 'shared_event' is ambiguous: it is provided by 'ecclash-alpha' and 'ecclash-beta'. "
            "Use a qualified name: 'ecclash-alpha/shared_event' or 'ecclash-beta/shared_event'."
        )
        with pytest.raises(
            ConfigError,
            match=r"env\.events\.e\.func.*'shared_event' is ambiguous.*"
            r"'ecclash-alpha/shared_event' or 'ecclash-beta/shared_event'",
        ):
            resolve_func("shared_event", "event", "env.events.e")
        with pytest.raises(AmbiguousNameError, match="'ecclash-alpha/ClashTask-v0' or 'ecclash-beta/ClashTask-v0'"):
            gym.make("ClashTask-v0")
        with pytest.raises(
            ConfigError, match=r"robot\.class_type.*'ecclash-alpha/ClashArm' or 'ecclash-beta/ClashArm'"
        ):
            RobotCfg.from_dict({"class_type": "ClashArm"}, "robot")
        with pytest.raises(ConfigError, match=r"sensor\.sensor_type.*ClashCam' is ambiguous"):
            SensorCfg.from_dict({"sensor_type": "ClashCam", "uid": "cam"}, "sensor")


@pytest.mark.parametrize("order", ORDERS, ids=["alpha-first", "beta-first"])
def test_configs_resolve_qualified_names(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], order: tuple[str, ...]
) -> None:
    from embodichain_core.managers.manager_base import resolve_func
    from embodichain_core.sim.cfg import RobotCfg, SensorCfg
    from embodichain_core.plugins import asset_registry, get_asset_root
    from embodichain_core.sim.data import get_data_path

    install(monkeypatch, dist_roots, order)
    with isolated_plugins(load_entry_points=True):
        beta = sys.modules["ecclash_beta"]
        assert resolve_func("ecclash-beta/shared_event", "event", "env.events.e") is beta.shared_event
        assert resolve_func("json:dumps", "event", "env.events.e") is json.dumps  # ':' is always an import path
        with pytest.raises(
            ConfigError,
            match="'ecclash-beta' provides no functor 'shared_evnt'. Did you mean 'ecclash-beta/shared_event'",
        ):
            resolve_func("ecclash-beta/shared_evnt", "event", "env.events.e")
        with pytest.raises(ConfigError, match="Did you mean 'ecclash-beta'"):
            resolve_func("ecclash-betta/shared_event", "event", "env.events.e")
        # a qualified name written with ":" (an import path's separator) gets the "/" spelling
        with pytest.raises(ConfigError, match="'ecclash-beta' is a plugin: .* written 'ecclash-beta/shared_event'"):
            resolve_func("ecclash-beta:shared_event", "event", "env.events.e")
        with pytest.raises(ConfigError, match=r"robot\.class_type.*unknown robot 'ecclash-beta:ClashArm'"):
            RobotCfg.from_dict({"class_type": "ecclash-beta:ClashArm"}, "robot")
        assert type(RobotCfg.from_dict({"class_type": "ecclash-beta/ClashArm"}, "robot")) is beta.ArmCfg
        cam = SensorCfg.from_dict({"sensor_type": "ecclash-beta/ClashCam", "uid": "cam"}, "sensor")
        assert type(cam) is beta.CamCfg
        assert Path(get_data_path("ecclash-beta:shared.txt")).read_text() == "ecclash_beta"
        assert Path(get_data_path("ecclash-alpha:shared.txt")).read_text() == "ecclash_alpha"
        assert asset_registry().qualified_names() == ["ecclash-alpha/data", "ecclash-beta/data"]
        assert get_asset_root("ecclash-beta/data") == Path(beta.DATA)
        with pytest.raises(AmbiguousNameError, match="asset root 'data' is ambiguous"):
            get_asset_root("data")


def _outcome() -> dict[str, Any]:
    """What a user sees: every name's resolution, the gym ids, the data root order."""
    from embodichain_core.sim.data import get_data_path

    out: dict[str, Any] = {"plugins": [(i.name, i.status) for i in list_plugins()]}
    for kind in ("functors", "robots", "sensors", "commands", "assets", "tasks"):
        registry = get_registry(kind)
        out[kind] = {q: registry.entry(q).target_repr for q in registry.qualified_names()}
        out[f"{kind}-clashes"] = registry.clashes()
        for name in registry.names():
            try:
                out[f"{kind}:{name}"] = registry.entry(name).provider
            except AmbiguousNameError as err:
                out[f"{kind}:{name}"] = str(err)
    out["gym"] = sorted(k for k in gym.registry if "Clash" in k or "Only-v0" in k)
    out["shared.txt"] = Path(get_data_path("shared.txt")).read_text()
    return out


def test_outcome_is_the_same_in_both_orders(monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path]) -> None:
    outcomes = []
    for order in ORDERS:
        with monkeypatch.context() as mp:
            install(mp, dist_roots, order)
            with isolated_plugins(load_entry_points=True):
                outcomes.append(_outcome())
    assert outcomes[0] == outcomes[1]
    assert "is ambiguous" in outcomes[0]["functors:shared_event"]
    assert outcomes[0]["gym"] == [
        "ClashTask-v0",
        "alphaOnly-v0",
        "betaOnly-v0",
        "ecclash-alpha/ClashTask-v0",
        "ecclash-alpha/alphaOnly-v0",
        "ecclash-beta/ClashTask-v0",
        "ecclash-beta/betaOnly-v0",
    ]


@pytest.mark.parametrize("order", ORDERS, ids=["alpha-first", "beta-first"])
def test_qualified_names_pick_the_provider_everywhere(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], order: tuple[str, ...]
) -> None:
    from embodichain_core.cli.main import main
    from embodichain_core.managers.manager_base import resolve_func
    from embodichain_core.sim.cfg import RobotCfg

    install(monkeypatch, dist_roots, order)
    with isolated_plugins(load_entry_points=True):
        beta = sys.modules["ecclash_beta"]
        assert resolve_func("ecclash-beta/shared_event", "event", "env.events.e") is beta.shared_event
        assert type(RobotCfg.from_dict({"class_type": "ecclash-beta/ClashArm"}, "robot")) is beta.ArmCfg
        assert gym.make("ecclash-beta/ClashTask-v0").unwrapped.who == "beta"
        vec = gym.make_vec("ecclash-beta/ClashTask-v0", num_envs=2, vectorization_mode="vector_entry_point")
        assert (vec.who, vec.kwargs) == ("beta", {"num_envs": 2})
        assert gym.make("ecclash-alpha/ClashTask-v0").unwrapped.who == "alpha"
        with pytest.raises(AmbiguousNameError):
            gym.make_vec("ClashTask-v0", num_envs=2, vectorization_mode="vector_entry_point")
        assert main(["ecclash-beta/hello", "x"]) == 0


def test_unregistering_one_provider_makes_the_bare_name_unique(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path]
) -> None:
    install(monkeypatch, dist_roots, DISTS)
    with isolated_plugins(load_entry_points=True) as pm:
        unregister_plugin("ecclash-alpha")
        assert pm.registry("functors").entry("shared_event").provider == "ecclash-beta"
        assert gym.registry["ClashTask-v0"].entry_point == "ecclash_beta:ClashEnv"
        assert "ecclash-alpha/ClashTask-v0" not in gym.registry
        assert pm.name_clashes() == []
    assert "ClashTask-v0" not in gym.registry
    assert "ecclash-beta/ClashTask-v0" not in gym.registry


def test_register_env_never_replaces_a_plugin_id(monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path]) -> None:
    from embodichain_core.envs.base_env import BaseEnv
    from embodichain_core.envs.registration import register_env

    install(monkeypatch, dist_roots, DISTS)
    with isolated_plugins(load_entry_points=True):
        spec = gym.registry["ClashTask-v0"]

        class Intruder(BaseEnv):
            pass

        with pytest.warns(
            UserWarning,
            match="task 'ClashTask-v0' is provided by ecclash-alpha, ecclash-beta; register_env keeps theirs",
        ):
            register_env("ClashTask-v0", override=True)(Intruder)
        assert gym.registry["ClashTask-v0"] is spec


def test_command_clash(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    from embodichain_core.cli.main import main

    install(monkeypatch, dist_roots, DISTS[::-1])
    with isolated_plugins(load_entry_points=True):
        assert main(["run-env", "ClashTask-v0", "--preview", "--quiet"]) == 2  # a config error, no traceback
        err = capsys.readouterr().err
        assert "task 'ClashTask-v0' is ambiguous" in err
        assert "Traceback" not in err
        assert main(["hello"]) == 2
        err = capsys.readouterr().err
        assert "command 'hello' is ambiguous" in err
        assert "'ecclash-alpha/hello' or 'ecclash-beta/hello'" in err
        assert main(["ecclash-alpha/hello", "y"]) == 0
        assert "hello from alpha ['y']" in capsys.readouterr().out
        assert main(["ecclash-alpha/helo"]) == 2
        assert "Did you mean 'ecclash-alpha/hello'" in capsys.readouterr().err
        assert main(["--help"]) == 0
        help_text = capsys.readouterr().out
        assert "ecclash-beta/hello" in help_text
        assert "ambiguous: provided by ecclash-alpha, ecclash-beta" in help_text


def test_entry_point_name_declared_by_two_distributions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path]
) -> None:
    squatter = write_dist(
        tmp_path / "squatter",
        "ecclash-squatter",
        "ecclash_squatter",
        PLUGIN_SOURCE.replace("@NAME@", "squatter"),
        entry_point="ecclash-alpha",
    )
    monkeypatch.syspath_prepend(str(squatter))
    install(monkeypatch, dist_roots, DISTS)
    names = [ep.name for ep in importlib.metadata.entry_points(group="embodichain")]
    assert names.count("ecclash-alpha") == 2  # pluggy would have kept only one of them
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # installing a third plugin breaks nothing: no failure, no warning
        with isolated_plugins(load_entry_points=True) as pm:
            infos = {i.name: i for i in list_plugins()}
            assert infos["ecclash-squatter"].status == infos["ecclash-alpha"].status == "loaded"
            assert infos["ecclash-squatter"].entry_point == "ecclash-alpha"
            assert pm.registry("functors").get("alpha_only").__module__ == "ecclash_alpha"
            assert pm.registry("functors").get("squatter_only").__module__ == "ecclash_squatter"
            assert pm.registry("functors").providers_of("shared_event") == [
                "ecclash-alpha",
                "ecclash-beta",
                "ecclash-squatter",
            ]


def test_list_shows_clashes_and_providers(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    from embodichain_core.cli.main import main

    install(monkeypatch, dist_roots, DISTS)
    with isolated_plugins(load_entry_points=True):
        assert main(["list", "plugins"]) == 0
        out = capsys.readouterr().out
        assert "name clashes (both plugins stay loaded; use the qualified names):" in out
        assert (
            "  functor 'shared_event' is provided by 'ecclash-alpha' and 'ecclash-beta' "
            "(use 'ecclash-alpha/shared_event' or 'ecclash-beta/shared_event')"
        ) in out
        assert (
            "task 'ClashTask-v0' is provided by 'ecclash-alpha' and 'ecclash-beta' "
            "(use 'ecclash-alpha/ClashTask-v0' or 'ecclash-beta/ClashTask-v0')" in out
        )
        row = next(line for line in out.splitlines() if line.startswith("ecclash-alpha "))
        assert row.split()[-1] == "6"  # one clash per kind
        assert main(["list", "plugins", "--json"]) == 0
        plugins = {r["name"]: r for r in json.loads(capsys.readouterr().out)}
        assert {
            "kind": "robots",
            "name": "ClashArm",
            "providers": ["ecclash-alpha", "ecclash-beta"],
            "qualified": ["ecclash-alpha/ClashArm", "ecclash-beta/ClashArm"],
        } in plugins["ecclash-beta"]["clashes"]
        assert plugins["embodichain-core"]["clashes"] == []
        assert main(["list", "functors"]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert lines[0].split()[:4] == ["NAME", "KIND", "CATEGORY", "PROVIDER"]
        rows = [line.split() for line in lines if line.startswith("shared_event")]
        assert [r[:2] for r in rows] == [["shared_event", "*"]] * 2
        assert [r[4] for r in rows] == ["ecclash-alpha", "ecclash-beta"]
        assert next(line for line in lines if line.startswith("beta_only")).split()[3] == "ecclash-beta"
        assert "  ecclash-beta/shared_event  (ecclash-beta)" in lines
        assert main(["list", "tasks", "--json"]) == 0
        tasks = {(r["name"], r["provider"]): r for r in json.loads(capsys.readouterr().out)}
        assert tasks[("ClashTask-v0", "ecclash-beta")]["qualified_name"] == "ecclash-beta/ClashTask-v0"
        assert tasks[("ClashTask-v0", "ecclash-beta")]["ambiguous"]
        assert not tasks[("alphaOnly-v0", "ecclash-alpha")]["ambiguous"]


def test_check_name_clashes_reports_installed_plugins(
    monkeypatch: pytest.MonkeyPatch, dist_roots: dict[str, Path]
) -> None:
    from embodichain_core.plugins import hookimpl
    from embodichain_core.testing import NameClashError, check_name_clashes

    install(monkeypatch, dist_roots, DISTS)
    alpha = importlib.import_module("ecclash_alpha")
    with pytest.raises(NameClashError) as info:  # its own installed copy is not a clash
        check_name_clashes(alpha)
    kinds = sorted((c.kind, c.providers) for c in info.value.clashes)
    assert kinds == sorted(
        (k, ("ecclash-alpha", "ecclash-beta")) for k in ("assets", "commands", "functors", "robots", "sensors", "tasks")
    )
    assert "functor 'shared_event' is provided by 'ecclash-alpha' and 'ecclash-beta'" in str(info.value)

    class Unique:
        @hookimpl
        def embodichain_register_functors(self, register: Any) -> None:
            register("unique_event", "json:dumps", kind="event")
            register("alpha_only", "json:loads", kind="event")

    clashes = check_name_clashes(Unique(), name="my-plugin", raise_on_clash=False)
    assert [(c.name, c.providers, c.qualified) for c in clashes] == [
        ("alpha_only", ("ecclash-alpha", "my-plugin"), ("ecclash-alpha/alpha_only", "my-plugin/alpha_only"))
    ]
    assert check_name_clashes(Unique(), name="my-plugin", ignore=["alpha_only"]) == []
    assert "my-plugin/alpha_only" not in get_registry("functors")  # the global state is untouched
