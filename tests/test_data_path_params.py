"""Functor params naming asset data are found by their ``DataPath`` annotation, not by name.

The annotations here are objects (no ``from __future__ import annotations``); the standard
functors' string annotations are covered by the functors plugin's tests.
"""

from typing import Any, Optional

import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import DataPath, EventCfg, EventManager
from embodichain_core.managers.param_rules import data_path_params
from embodichain_core.plugins import hookimpl, isolated_plugins, register_plugin

SEEN: dict[str, Any] = {}


def ec_test_load_textures(
    env: Any,
    env_ids: Any,
    textures: DataPath,
    extra: Optional[list[DataPath]] = None,
    spare: Optional[DataPath] = None,
    folder_path: Any = None,
) -> None:
    SEEN.update(textures=textures, extra=extra, folder_path=folder_path)


class TexturePlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register("ec_test_load_textures", ec_test_load_textures, kind="event")


@pytest.fixture
def data_root(tmp_path, monkeypatch) -> Any:
    """A data root holding ``wood/`` and ``marble/``; the test functor registered by name."""
    for name in ("wood", "marble"):
        (tmp_path / name).mkdir()
    monkeypatch.setenv("EMBODICHAIN_DATA_ROOT", str(tmp_path))
    with isolated_plugins():
        register_plugin(TexturePlugin(), name="ec-test-textures")
        yield tmp_path


def _validate(**params: Any) -> dict:
    section = {"tex": EventCfg(func="ec_test_load_textures", mode="reset", params=params)}
    return EventManager.validate_section(None, section)


def test_annotated_params_are_data_paths_whatever_their_name() -> None:
    assert data_path_params(ec_test_load_textures, 2) == {"textures": False, "extra": True, "spare": False}


def test_annotated_data_path_is_checked_and_unannotated_is_not(data_root) -> None:
    checked = _validate(textures="wood", extra=["marble", "wood/"], folder_path="NoSuchFolder/")
    assert checked["tex"].cfg.params["folder_path"] == "NoSuchFolder/"  # unannotated: as given
    with pytest.raises(ConfigError) as err:
        _validate(textures="wod")
    assert err.value.path == "env.events.tex.params.textures"
    assert "functor 'ec_test_load_textures'" in err.value.reason
    assert "wod" in err.value.reason
    with pytest.raises(ConfigError) as err:
        _validate(textures="wood", extra=["marble", "granite"])
    assert err.value.path == "env.events.tex.params.extra[1]"
    with pytest.raises(ConfigError) as err:
        _validate(textures="wood", spare="granite")
    assert err.value.path == "env.events.tex.params.spare"
    with pytest.raises(ConfigError, match="expected a string, got int 3"):  # a DataPath is a str
        _validate(textures=3)
    _validate(textures="wood/*.png")  # a glob pattern is left to the functor


def test_env_passes_data_paths_as_given(data_root, make_env) -> None:
    env = make_env(
        events={
            "tex": EventCfg(
                func="ec_test_load_textures",
                mode="reset",
                params={"textures": "wood", "extra": [str(data_root / "marble")], "folder_path": "NoSuchFolder/"},
            )
        }
    )
    env.reset()
    assert SEEN == {"textures": "wood", "extra": [str(data_root / "marble")], "folder_path": "NoSuchFolder/"}
