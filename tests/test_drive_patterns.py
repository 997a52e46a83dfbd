"""``{joint name or regex: value}`` drive mappings: an exact joint name wins over every
pattern whatever the order, and two patterns that give one joint different values are a
ConfigError naming both, the joint and the config key (never the first one silently)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import torch
from robot_files import urdf_robot_section, write_urdf_arm

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import RobotCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.scene_build.drive_values import joint_value

KEY = "robot.drive_pros.stiffness"


@pytest.mark.parametrize("values", [{".*": 1e4, "finger_joint": 10.0}, {"finger_joint": 10.0, ".*": 1e4}])
def test_an_exact_name_wins_over_a_pattern_in_either_order(values: dict) -> None:
    assert joint_value(values, "finger_joint", KEY) == 10.0
    assert joint_value(values, "elbow", KEY) == 1e4


def test_patterns_that_agree_give_their_value_and_no_match_gives_nan() -> None:
    values = {"finger_.*": 10.0, ".*_joint": 10.0, "elbow": 3.0}
    assert joint_value(values, "finger_joint", KEY) == 10.0
    assert math.isnan(joint_value({"finger_.*": 10.0}, "elbow", KEY))  # the caller's default applies
    assert joint_value(2.5, "anything", KEY) == 2.5


@pytest.mark.parametrize("values", [{".*": 1e4, "finger_.*": 10.0}, {"finger_.*": 10.0, ".*": 1e4}])
def test_two_patterns_with_different_values_name_both_the_joint_and_the_key(values: dict) -> None:
    with pytest.raises(ConfigError) as err:
        joint_value(values, "finger_joint", KEY)
    text = str(err.value)
    assert err.value.path == KEY
    for part in ("'finger_joint'", "'.*'", "'finger_.*'", "10000", "own entry"):
        assert part in text, text


def test_a_pattern_that_is_no_regex_is_a_config_error() -> None:
    with pytest.raises(ConfigError) as err:
        joint_value({"finger_[": 1.0}, "finger_joint", KEY)
    assert err.value.path == f"{KEY}.finger_["


def _scene(tmp_path: Path, stiffness: dict) -> Scene:
    section = urdf_robot_section(write_urdf_arm(tmp_path))
    section["drive_pros"] = {**section["drive_pros"], "stiffness": stiffness}
    scene = Scene(SimulationManagerCfg(), num_envs=1)
    scene.add_robot(RobotCfg.from_dict(section))
    scene.build()
    return scene


def test_the_build_gives_the_exact_entry_to_its_joint(tmp_path: Path) -> None:
    scene = _scene(tmp_path, {".*": 1e4, "finger_left": 10.0})
    robot = scene["arm"]
    ids, _ = robot.find_joints(["finger_left", "elbow"], preserve_order=True)
    stiffness, _ = robot.get_joint_drive(joint_ids=ids)
    assert torch.allclose(stiffness, torch.tensor([[10.0, 1e4]]))


def test_the_build_rejects_conflicting_patterns_at_their_config_key(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as err:
        _scene(tmp_path, {".*": 1e4, "finger_.*": 10.0})
    assert err.value.path.endswith("drive_pros.stiffness"), err.value.path
    assert "'finger_left'" in str(err.value)
    assert "'finger_.*'" in str(err.value)
