"""get_data_path: resolution order, plugin data roots, and the not-found message."""

from __future__ import annotations

import os
import types
from typing import Callable

import pytest

from embodichain_core.plugins import manager as plugin_manager
from embodichain_core.plugins.hookspecs import AssetRegister
from embodichain_core.plugins.registry import Registry
from embodichain_core.sim import data
from embodichain_core.sim.data import DataPathNotFoundError, data_roots, get_data_path, register_data_root


def _touch(path: os.PathLike[str] | str) -> str:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as handle:
        handle.write("x")
    return str(path)


@pytest.fixture
def roots(tmp_path, monkeypatch):
    """An env root, no runtime roots, and an empty ``assets`` registry of the plugin host."""
    env_root = tmp_path / "env_root"
    env_root.mkdir()
    monkeypatch.setenv("EMBODICHAIN_DATA_ROOT", str(env_root))
    monkeypatch.setattr(data, "_runtime_roots", [])
    registry = Registry("assets", noun="asset root")
    calls: list[int] = []
    fake_get = lambda kind: calls.append(1) or registry if kind == "assets" else pytest.fail(kind)  # noqa: E731
    monkeypatch.setattr(plugin_manager, "get_registry", fake_get)  # the real one loads the plugins first
    return types.SimpleNamespace(env=env_root, tmp=tmp_path, registry=registry, load_calls=calls)


def _plugin_root(roots, name: str, target: str | Callable[[], str]) -> None:
    """Register a data root the way a plugin's ``embodichain_register_assets`` hook does."""
    AssetRegister(roots.registry, provider=f"{name}-provider")(name, target)


def test_absolute_path_is_returned_unchanged(roots):
    file = _touch(roots.tmp / "abs" / "mesh.ply")
    assert get_data_path(file) == file


def test_missing_absolute_path_raises_with_siblings(roots):
    _touch(roots.tmp / "abs" / "mesh.ply")
    with pytest.raises(DataPathNotFoundError) as err:
        get_data_path(str(roots.tmp / "abs" / "mesh.plyy"))
    assert "mesh.ply" in str(err.value)
    assert isinstance(err.value, FileNotFoundError)
    # the hint names the documented way for a plugin, the hook
    assert "embodichain_register_assets hook" in str(err.value)
    assert "register_data_root" not in str(err.value)


def test_env_root_wins_over_runtime_and_plugin_roots(roots):
    env_file = _touch(roots.env / "Obj" / "a.ply")
    runtime = roots.tmp / "runtime"
    _touch(runtime / "Obj" / "a.ply")
    register_data_root(runtime)
    plugin = roots.tmp / "plugin"
    _touch(plugin / "Obj" / "a.ply")
    _plugin_root(roots, "pack", str(plugin))
    assert get_data_path("Obj/a.ply") == env_file


def test_runtime_root_before_plugin_roots(roots):
    runtime = roots.tmp / "runtime"
    expected = _touch(runtime / "Obj" / "b.ply")
    register_data_root(runtime)
    _plugin_root(roots, "pack", str(roots.tmp / "plugin"))
    _touch(roots.tmp / "plugin" / "Obj" / "b.ply")
    assert get_data_path("Obj/b.ply") == expected


def test_plugin_roots_in_registration_order_and_callable_targets(roots):
    first, second = roots.tmp / "first", roots.tmp / "second"
    _touch(second / "Only" / "second.obj")
    shared = _touch(first / "Both" / "c.stl")
    _touch(second / "Both" / "c.stl")
    calls: list[int] = []
    _plugin_root(roots, "zz-first", lambda: calls.append(1) or str(first))  # sorts last by name
    _plugin_root(roots, "aa-second", str(second))
    assert get_data_path("Both/c.stl") == shared
    assert get_data_path("Only/second.obj") == str(second / "Only" / "second.obj")
    assert data_roots()[-2:] == [str(first), str(second)]
    assert calls == [1], "a callable root is called once"
    assert roots.load_calls, "the registry is read through get_registry, which loads the plugins"


def test_folder_keeps_trailing_slash(roots):
    _touch(roots.env / "TableWare" / "tableware" / "fork" / "standard_fork_scale.ply")
    path = get_data_path("TableWare/tableware/fork/")
    assert path.endswith("/fork/")
    assert os.path.isdir(path)
    assert get_data_path("TableWare/tableware/fork").endswith("/fork")


def test_not_found_lists_roots_and_closest_names(roots):
    _touch(roots.env / "TableWare" / "tableware" / "fork" / "standard_fork_scale.ply")
    plugin = roots.tmp / "plugin"
    _touch(plugin / "CircleTableSimple" / "circle_table_simple.ply")
    _plugin_root(roots, "pack", str(plugin))
    missing = str(roots.tmp / "missing_runtime")
    register_data_root(missing)
    with pytest.raises(DataPathNotFoundError) as err:
        get_data_path("CircleTableSimpel/circle_table_simple.ply")
    message = str(err.value)
    for root in (str(roots.env), str(plugin), missing):
        assert root in message
    assert "(missing)" in message
    assert "'CircleTableSimple/circle_table_simple.ply'" in message
    assert err.value.roots == data_roots()
    with pytest.raises(DataPathNotFoundError) as err:
        get_data_path("TableWare/tableware/forks/")
    assert "'TableWare/tableware/fork/'" in str(err.value)


def test_default_root_when_env_unset(roots, monkeypatch):
    monkeypatch.delenv("EMBODICHAIN_DATA_ROOT")
    assert data_roots()[0] == os.path.expanduser(os.path.join("~", ".cache", "embodichain_data"))


def test_register_data_root_is_idempotent(roots):
    register_data_root(roots.tmp / "r")
    register_data_root(str(roots.tmp / "r"))
    assert data_roots().count(str(roots.tmp / "r")) == 1
