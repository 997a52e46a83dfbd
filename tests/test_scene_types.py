"""A scene entry that is still a plain mapping (a config subclass redeclared its field as
``List[Any]``) is a ConfigError at its path naming the declaration and its fix, from
``run-env --preview`` and from ``validate()`` alike, never ``'dict' object has no attribute``."""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any, Iterator, List

import gymnasium as gym
import pytest
from core_testlib import base_cfg
from scenes import ARM_MJCF

from embodichain_core.cli import run_env
from embodichain_core.config.errors import ConfigError
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.envs.registration import register_env
from embodichain_core.utils.configclass import configclass

CAMERA = {"sensor_type": "Camera", "uid": "cam", "width": 64, "height": 48, "init_pos": [1.0, 0.0, 1.0]}


@configclass
class LooseSensorCfg(EmbodiedEnvCfg):
    """Redeclares ``sensor`` with a looser type: the loader keeps its entries as dicts."""

    sensor: List[Any] = []


class LooseSensorTask(EmbodiedEnv):
    cfg_cls = LooseSensorCfg


@pytest.fixture
def task_id() -> Iterator[str]:
    uid = f"LooseSensor{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(LooseSensorTask)
    yield uid
    gym.registry.pop(uid, None)


def test_run_env_preview_names_the_entry_the_declaration_and_the_fix(
    task_id: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "cfg.json"
    data = {"id": task_id, "num_envs": 1, "env": {"verbose": False}, "robot": {"uid": "arm", "mjcf": ARM_MJCF}}
    config.write_text(json.dumps({**data, "sensor": [CAMERA]}))
    assert run_env.main(["--gym_config", str(config), "--preview", "--quiet"]) != 0
    err = capsys.readouterr().err
    assert "AttributeError" not in err
    for part in ("sensor[0]: is a plain mapping", "LooseSensorCfg declares `sensor: List[Any]`"):
        assert part in err, err
    assert "declare `sensor: List[SensorCfg]` as EmbodiedEnvCfg does" in err, err


def test_validate_names_a_loose_robot_declaration() -> None:
    @configclass
    class LooseRobotCfg(EmbodiedEnvCfg):
        robot: Any = None

    cfg = LooseRobotCfg(**{k: getattr(base_cfg(), k) for k in ("num_envs", "seed", "rigid_object", "background")})
    cfg.robot = {"uid": "arm", "mjcf": ARM_MJCF}
    with pytest.raises(ConfigError) as err:
        cfg.validate(memory=False, functors=False)
    assert err.value.path == "robot"
    assert "LooseRobotCfg declares `robot: Any`" in str(err.value)
    assert "`robot: RobotCfg`" in str(err.value)


def test_a_mapping_put_in_by_code_says_to_build_it_from_its_class() -> None:
    cfg = base_cfg()
    cfg.rigid_object = [*cfg.rigid_object, {"uid": "ball"}]
    with pytest.raises(ConfigError) as err:
        cfg.validate(memory=False, functors=False)
    assert err.value.path == "rigid_object[1]"
    assert "build it from its config class (`List[RigidObjectCfg]`)" in str(err.value)
