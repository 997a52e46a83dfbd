"""The gym configs the installed plugins ship (``<package>/**/configs/*.json|yaml``) and the
default configs of their registered tasks set no field that has no MuJoCo equivalent, so
they build without an ``IgnoredFieldWarning``; a user config that sets one still gets it.

The one exception is ``modular_env.json``, the JSON twin of the modular-env tutorial, whose
code is kept line for line with EmbodiChain's tutorial (``plugins/embodichain-tasks/tests/
test_tasks_modular_env.py``): it sets the table's PhysX restitution and dynamic friction,
and its warning names exactly those two."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import warnings
from pathlib import Path
from typing import Any

import pytest

from embodichain_core.config.ignored import IgnoredFieldWarning, ignored_fields, warn_ignored
from embodichain_core.config.loader import load_gym_config
from embodichain_core.plugins import get_registry
from embodichain_core.plugins.manager import named_entry_points


def shipped_configs() -> list[Path]:
    """Every ``configs/*.json``/``.yaml`` inside the package of an installed plugin."""
    found: set[Path] = set()
    for _, ep in named_entry_points():
        spec = importlib.util.find_spec(ep.value.split(":")[0].split(".")[0])
        for root in (spec.submodule_search_locations or []) if spec else []:
            for pattern in ("**/configs/*.json", "**/configs/*.yaml", "**/configs/*.yml"):
                found.update(Path(root).glob(pattern))
    return sorted(found)


CONFIGS = shipped_configs()
#: Configs that reproduce code kept line for line with EmbodiChain's (their PhysX values
#: included), with exactly the ignored fields they are expected to name.
EXEMPT = {
    "modular_env.json": {"background[0].attrs.restitution", "background[0].attrs.dynamic_friction"},
}


def _load(path: Path) -> tuple[Any, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _, cfg, _ = load_gym_config(str(path), {"verbose": False})
    return cfg, caught


def test_the_installed_plugins_ship_configs() -> None:
    names = {p.name for p in CONFIGS}
    if any(name == "embodichain-tasks" for name, _ in named_entry_points()):
        assert {"main_job.json", "push_cube.json"} <= names, names


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: f"{p.parent.parent.name}/{p.name}")
def test_a_shipped_config_loads_without_warnings_and_sets_no_ignored_field(path: Path) -> None:
    cfg, caught = _load(path)
    assert [str(w.message) for w in caught] == []
    if path.name in EXEMPT:  # the tutorial's JSON twin (docs/tutorial_modular_env.md)
        assert {f.path for f in ignored_fields(cfg)} == EXEMPT[path.name]
        return
    assert [f"{f.path} = {f.value!r}" for f in ignored_fields(cfg)] == []
    with warnings.catch_warnings():
        warnings.simplefilter("error", IgnoredFieldWarning)  # what the env's build runs
        assert warn_ignored(cfg) == []


def test_the_registered_tasks_default_configs_set_no_ignored_field() -> None:
    checked = []
    for entry in get_registry("tasks").entries():
        cfg_cls = getattr(entry.resolve(), "cfg_cls", None)
        try:
            cfg = cfg_cls() if cfg_cls is not None else None
        except Exception:  # noqa: BLE001 - a config with required fields (a JSON-only task) has no default
            continue
        if cfg is not None and dataclasses.is_dataclass(getattr(cfg, "robot", None)):  # JSON-only: robot missing
            checked.append(entry.name)
            assert [f.path for f in ignored_fields(cfg)] == [], entry.name
    if CONFIGS:
        assert checked, "no registered task has a default config"


def test_a_user_config_that_sets_an_ignored_field_still_warns(tmp_path: Path) -> None:
    source = next((p for p in CONFIGS if p.name == "push_cube.json"), None)
    if source is None:
        pytest.skip("embodichain-tasks (push_cube.json) is not installed")
    data = json.loads(source.read_text())
    data["rigid_object"][0].setdefault("attrs", {})["restitution"] = 0.3
    user = tmp_path / "mine.json"
    user.write_text(json.dumps(data))
    cfg, _ = _load(user)
    with pytest.warns(IgnoredFieldWarning, match=r"rigid_object\[0\]\.attrs\.restitution = 0\.3"):
        warn_ignored(cfg)
