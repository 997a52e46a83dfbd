"""Registries: clashes and qualified names, unknown names, lazy targets, typed register objects."""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path

import pytest

from embodichain_core.plugins.hookspecs import (
    AssetRegister,
    FunctorRegister,
    RobotRegister,
    SensorRegister,
    new_registries,
)
from embodichain_core.plugins.registry import (
    AmbiguousNameError,
    DuplicateRegistrationError,
    Registry,
    TargetImportError,
    UnknownNameError,
)


def _randomize_light() -> None:
    """Randomize the light color and intensity.

    More text.
    """


@pytest.fixture
def registries() -> dict[str, Registry]:
    return new_registries()


def test_add_get_and_queries() -> None:
    reg = Registry("functors")
    entry = reg.add("randomize_light", _randomize_light, provider="plugin-a", meta={"kind": "event"})
    assert reg.get("randomize_light") is _randomize_light
    assert reg.entry("randomize_light") is entry
    assert "randomize_light" in reg
    assert "other" not in reg
    assert reg.names() == ["randomize_light"]
    assert reg.entries() == [entry]
    assert entry.provider == "plugin-a"
    assert entry.meta["kind"] == "event"
    assert len(reg) == 1
    assert list(reg) == ["randomize_light"]


def test_same_name_two_providers_both_kept_bare_name_ambiguous() -> None:
    reg = Registry("functors")
    reg.add("randomize_light", "json:dumps", provider="plugin-b")
    reg.add("randomize_light", "json:loads", provider="plugin-a")
    reg.add("joint_pos", "json:JSONDecoder", provider="plugin-b")
    assert reg.get("plugin-a/randomize_light") is json.loads
    assert reg.get("plugin-b/randomize_light") is json.dumps
    assert reg.get("joint_pos") is json.JSONDecoder  # unique bare names still resolve
    assert reg.names() == ["joint_pos", "randomize_light"]
    assert len(reg) == 3
    assert reg.clashes() == {"randomize_light": ["plugin-a", "plugin-b"]}
    assert "randomize_light" in reg
    assert "plugin-a/randomize_light" in reg
    assert "plugin-a/joint_pos" not in reg
    with pytest.raises(AmbiguousNameError) as info:
        reg.get("randomize_light")
    assert str(info.value) == (
        "functor 'randomize_light' is ambiguous: it is provided by 'plugin-a' and 'plugin-b'. Use a "
        "qualified name: 'plugin-a/randomize_light' or 'plugin-b/randomize_light'."
    )
    assert info.value.providers == ["plugin-a", "plugin-b"]
    assert not isinstance(info.value, KeyError)
    reg.drop("plugin-b")
    assert reg.get("randomize_light") is json.loads  # one provider left: the bare name resolves


def test_same_provider_twice_with_another_target_is_an_error() -> None:
    reg = Registry("functors")
    reg.add("randomize_light", "json:dumps", provider="plugin-a")
    with pytest.raises(DuplicateRegistrationError) as info:
        reg.add("randomize_light", "json:loads", provider="plugin-a")
    assert "'randomize_light' is registered twice" in str(info.value)
    assert "'plugin-a'" in str(info.value)


def test_qualified_lookups_of_unknown_names_suggest() -> None:
    reg = Registry("functors")
    reg.add("randomize_light", "json:dumps", provider="plugin-a")
    with pytest.raises(
        UnknownNameError,
        match="'plugin-a' provides no functor 'randomize_ligth'. Did you mean 'plugin-a/randomize_light'",
    ):
        reg.get("plugin-a/randomize_ligth")
    with pytest.raises(UnknownNameError, match="no plugin named 'plugin-b' provides functors. Did you mean 'plugin-a'"):
        reg.get("plugin-b/randomize_light")


def test_a_qualified_name_spelled_with_a_colon_suggests_the_slash() -> None:
    reg = Registry("functors")
    reg.add("randomize_light", "json:dumps", provider="plugin-a")
    with pytest.raises(
        UnknownNameError, match="unknown functor 'plugin-a:randomize_light'. Did you mean 'plugin-a/randomize_light'"
    ):
        reg.get("plugin-a:randomize_light")
    assert reg.find("json:dumps") is None  # ':' is an import path's separator: never a registered name


@pytest.mark.parametrize("name", ["a:b", "a/b", ""])
def test_names_cannot_contain_the_separators(name: str) -> None:
    with pytest.raises(ValueError, match="without '/' or ':'"):
        Registry("functors").add(name, "json:dumps", provider="p")


def test_identical_reregistration_is_a_noop() -> None:
    reg = Registry("functors")
    first = reg.add("dumps", "json:dumps", provider="plugin-a")
    assert reg.add("dumps", "json:dumps", provider="plugin-a") is first


def test_unknown_name_suggests_closest() -> None:
    reg = Registry("functors")
    for name in ("randomize_light", "randomize_mass", "joint_pos"):
        reg.add(name, "json:dumps", provider="p")
    with pytest.raises(UnknownNameError) as info:
        reg.get("randomise_light")
    err = info.value
    assert isinstance(err, KeyError)  # what the config code catches for an unknown name
    assert str(err).startswith("unknown functor 'randomise_light'. Did you mean 'randomize_light'")
    assert err.matches[0] == "randomize_light"


def test_unknown_name_in_empty_registry_hints_at_plugins() -> None:
    with pytest.raises(UnknownNameError, match="no robots are registered"):
        Registry("robots").get("DexforceW1")


def test_lazy_target_imported_on_first_get(monkeypatch: pytest.MonkeyPatch) -> None:
    reg = Registry("functors")
    entry = reg.add("thing", "ec_test_lazy_mod:Outer.inner", provider="p")
    assert entry.lazy
    assert not entry.resolved
    module = types.ModuleType("ec_test_lazy_mod")
    module.Outer = types.SimpleNamespace(inner=_randomize_light)
    monkeypatch.setitem(sys.modules, "ec_test_lazy_mod", module)
    assert reg.get("thing") is _randomize_light
    assert entry.resolved
    assert reg.add("dumps", "json:dumps", provider="p").resolve() is json.dumps


def test_import_error_names_entry_and_provider() -> None:
    reg = Registry("functors")
    reg.add("broken", "ec_no_such_module_xyz:func", provider="plugin-z")
    with pytest.raises(TargetImportError) as info:
        reg.get("broken")
    msg = str(info.value)
    assert "'broken'" in msg
    assert "'plugin-z'" in msg
    assert "ec_no_such_module_xyz" in msg
    assert isinstance(info.value.__cause__, ModuleNotFoundError)


@pytest.mark.parametrize("bad", ["json:", "json dumps:x", "a:b c"])
def test_malformed_lazy_target_rejected(bad: str) -> None:
    with pytest.raises(ValueError, match="module:attr"):
        Registry("functors").add("x", bad, provider="p")


def test_functor_register_validates_kind(registries: dict[str, Registry]) -> None:
    register = FunctorRegister(registries["functors"], "plugin-a")
    with pytest.raises(ValueError, match="Did you mean 'event'"):
        register("randomize_light", _randomize_light, kind="evnt")
    entry = register("randomize_light", _randomize_light, kind="event", category="randomization.visual")
    assert entry.meta == {"kind": "event", "category": "randomization.visual", "description": ""}
    assert entry.description == "Randomize the light color and intensity."


def test_functor_description_from_docstring_when_resolved(
    registries: dict[str, Registry], monkeypatch: pytest.MonkeyPatch
) -> None:
    module = types.ModuleType("ec_test_functors")
    module.randomize_light = _randomize_light
    monkeypatch.setitem(sys.modules, "ec_test_functors", module)
    register = FunctorRegister(registries["functors"], "plugin-a")
    entry = register("randomize_light", "ec_test_functors:randomize_light", kind="event")
    assert entry.description == ""  # not imported yet
    entry.resolve()
    assert entry.description == "Randomize the light color and intensity."
    explicit = register("other", "ec_test_functors:randomize_light", kind="event", description="Mine")
    assert explicit.description == "Mine"


def test_robot_lookup_ignores_case_and_cfg_suffix(registries: dict[str, Registry]) -> None:
    class DexforceW1Cfg:
        pass

    RobotRegister(registries["robots"], "robots")("DexforceW1", DexforceW1Cfg)
    robots = registries["robots"]
    for name in ("DexforceW1", "dexforcew1", "DexforceW1Cfg", "DEXFORCEW1CFG"):
        assert robots.get(name) is DexforceW1Cfg
    assert robots.names() == ["DexforceW1"]
    RobotRegister(robots, "other")("dexforcew1cfg", "json:dumps")
    assert robots.get("other/DexforceW1") is json.dumps
    assert robots.get("robots/dexforcew1Cfg") is DexforceW1Cfg
    with pytest.raises(AmbiguousNameError, match="'other/dexforcew1cfg' or 'robots/DexforceW1'"):
        robots.get("DexforceW1Cfg")


def test_sensor_register_keeps_both_classes(registries: dict[str, Registry]) -> None:
    SensorRegister(registries["sensors"], "sensors")("StereoCamera", "json:JSONDecoder", "json:JSONEncoder")
    entry = registries["sensors"].entry("stereocamera")
    assert entry.resolve() is json.JSONDecoder
    assert entry.resolve_meta("sensor_class") is json.JSONEncoder


def test_asset_register_paths_and_callables(registries: dict[str, Registry], tmp_path: Path) -> None:
    register = AssetRegister(registries["assets"], "assets")
    register("pack", str(tmp_path))
    register("lazy_pack", lambda: tmp_path)
    assert registries["assets"].get("pack") == str(tmp_path)  # a path is never imported
    assert registries["assets"].get("lazy_pack")() == tmp_path
    with pytest.raises(TypeError):
        register("bad", 42)
