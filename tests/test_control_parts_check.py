"""A wrong joint name in ``robot.control_parts`` is a ConfigError at
``robot.control_parts.<part>[i]`` with a suggestion: at validation for a file-based robot
(before anything is built), at the build for a generated one; ``run-env`` exits 2."""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any, Iterator

import gymnasium as gym
import pytest
from core_testlib import base_cfg
from scenes import ARM_MJCF

from embodichain_core.cli import run_env
from embodichain_core.config.errors import ConfigError
from embodichain_core.config.joint_check import check_robot_joints, match_part_patterns
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.envs.registration import register_env
from embodichain_core.sim.cfg import RobotCfg


def test_a_wrong_joint_name_is_named_by_its_path_with_the_closest_joint() -> None:
    cfg = base_cfg()
    cfg.robot.control_parts = {"arm": ["joint1", "jiont2"]}
    with pytest.raises(ConfigError) as err:
        cfg.validate(memory=False)
    assert err.value.path == "robot.control_parts.arm[1]"
    assert "Did you mean 'joint2'" in err.value.reason


def test_regexes_match_in_order_and_a_bad_regex_is_named() -> None:
    names = ["j1", "j2", "j3"]
    assert match_part_patterns(names, "robot", "arm", ["j3", "j[12]"]) == [2, 0, 1]
    with pytest.raises(ConfigError) as err:
        match_part_patterns(names, "robot", "arm", ["j(1"])
    assert err.value.path == "robot.control_parts.arm[0]"
    assert "not a valid regex" in err.value.reason


def test_a_file_based_robot_is_checked_before_the_build(monkeypatch: pytest.MonkeyPatch) -> None:
    from embodichain_core.envs import env_build

    cfg = base_cfg()
    cfg.robot.control_parts = {"arm": ["joint[1-7]"], "hand": ["finger"]}
    built = []
    monkeypatch.setattr(env_build, "bind_extensions", lambda env: built.append(env))
    with pytest.raises(ConfigError) as err:
        EmbodiedEnv(cfg)
    assert err.value.path == "robot.control_parts.hand[0]"
    assert built == []  # the scene was not started


class GeneratedArmCfg(RobotCfg):
    """A robot generated in code (like a robot plugin's): checked when it is built."""

    def build_spec(self) -> Any:
        import mujoco

        return mujoco.MjSpec.from_string(ARM_MJCF)


def test_a_generated_robot_is_checked_at_the_build() -> None:
    robot = GeneratedArmCfg(uid="arm", control_parts={"arm": ["j1", "j4"]})
    check_robot_joints(robot)  # its joints are known only once generated
    cfg = base_cfg(robot=robot, control_parts=["arm"])
    with pytest.raises(ConfigError) as err:
        EmbodiedEnv(cfg)
    assert err.value.path == "robot.control_parts.arm[1]"
    assert "no joint of the robot matches 'j4'. Valid choices: 'j1', 'j2', 'j3'" in err.value.reason


@pytest.fixture
def task_id() -> Iterator[str]:
    uid = f"ControlParts{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(EmbodiedEnv)
    yield uid
    gym.registry.pop(uid, None)


def test_run_env_reports_it_as_a_config_error_and_exits_2(
    tmp_path: Path, task_id: str, capsys: pytest.CaptureFixture
) -> None:
    config = tmp_path / "c.json"
    data = {
        "id": task_id,
        "num_envs": 1,
        "max_episode_steps": 2,
        "env": {"verbose": False, "control_parts": ["arm"]},
        "robot": {"uid": "arm", "mjcf": ARM_MJCF, "control_parts": {"arm": ["j1", "j_2"]}},
    }
    config.write_text(json.dumps(data))
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "robot.control_parts.arm[1]: no joint of the robot matches 'j_2'. Did you mean 'j2'" in err
    assert "Traceback" not in err


def test_load_gym_config_checks_a_file_based_robot() -> None:
    from embodichain_core.config.loader import load_gym_config

    robot = {"uid": "arm", "mjcf": ARM_MJCF, "control_parts": {"arm": ["j1", "j9"]}}
    data = {"id": "Any-v0", "env": {}, "robot": robot}
    with pytest.raises(ConfigError) as err:
        load_gym_config(data)
    assert err.value.path == "robot.control_parts.arm[1]"
    data["robot"]["control_parts"] = {"arm": ["j[1-3]"]}
    assert load_gym_config(data)[0] == "Any-v0"
