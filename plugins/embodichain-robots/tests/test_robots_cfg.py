"""Config surface of the robots: from_dict, merges, errors, registry lookup."""

from __future__ import annotations

import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import RobotCfg
from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg
from embodichain_robots.kinematics.solver import IKSolverCfg
from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg

TUTORIAL = {"uid": "dexforce_w1", "version": "v021", "arm_kind": "anthropomorphic", "init_pos": [0, 0, 0]}


def test_tutorial_dict() -> None:
    cfg = DexforceW1Cfg.from_dict(TUTORIAL)
    assert cfg.uid == "dexforce_w1"
    assert cfg.version == "v021"
    assert cfg.arm_kind == "anthropomorphic"
    assert cfg.hand_types == {"left": "BRAINCO_HAND", "right": "BRAINCO_HAND"}
    assert cfg.fix_base
    assert cfg.disable_self_collision
    assert cfg.control_parts["left_eef"][0] == "LEFT_HAND_THUMB1"
    assert isinstance(cfg.solver_cfg["left_arm"], IKSolverCfg)


@pytest.mark.parametrize("cls", [DexforceW1Cfg, SevenDofArmCfg])
def test_unknown_key_names_the_key(cls: type) -> None:
    with pytest.raises(ConfigError, match="arm_knd"):
        cls.from_dict({"uid": "r", "arm_knd": "industrial"})


@pytest.mark.parametrize(
    ("data", "path"),
    [
        ({"version": "v030"}, "version"),
        ({"arm_kind": "humanoid"}, "arm_kind"),
        ({"hand_types": {"left": "robotiq"}}, "hand_types.left"),
        ({"hand_types": {"middle": "BRAINCO_HAND"}}, "hand_types.middle"),
        ({"hand_attach_xposes": {"left": [[1, 0], [0, 1]]}}, "hand_attach_xposes.left"),
        ({"drive_pros": {"stifness": 1.0}}, "drive_pros.stifness"),
        ({"solver_cfg": {"left_arm": {"tcpp": []}}}, "solver_cfg.left_arm.tcpp"),
    ],
)
def test_bad_values_name_their_path(data: dict, path: str) -> None:
    with pytest.raises(ConfigError) as err:
        DexforceW1Cfg.from_dict({"uid": "w1", **data})
    assert err.value.path == path


def test_nested_path_is_prefixed() -> None:
    with pytest.raises(ConfigError) as err:
        RobotCfg.from_dict({"robot_type": "DexforceW1", "version": "v9"}, "robot")
    assert err.value.path == "robot.version"


def test_enums_and_case_are_accepted() -> None:
    from embodichain_robots.dexforce_w1.params import DexforceW1ArmKind, DexforceW1Version

    cfg = DexforceW1Cfg(
        version=DexforceW1Version.V025, arm_kind=DexforceW1ArmKind.INDUSTRIAL, hand_types={"LEFT": "brainco_hand"}
    )
    assert (cfg.version, cfg.arm_kind, cfg.hand_types) == ("v025", "industrial", {"left": "BRAINCO_HAND"})
    assert "right_eef" not in cfg.control_parts


def test_without_default_eef() -> None:
    cfg = DexforceW1Cfg.from_dict({"with_default_eef": False})
    assert cfg.hand_types == {}
    assert "left_eef" not in cfg.control_parts


def test_drive_pros_deep_merge() -> None:
    cfg = DexforceW1Cfg.from_dict({"drive_pros": {"stiffness": {"LEFT_J1": 5e3}, "max_effort": 50.0}})
    stiffness = cfg.drive_pros.stiffness
    assert list(stiffness)[0] == "LEFT_J1"
    assert stiffness["(ANKLE|KNEE|BUTTOCK|WAIST)"] == 1e6
    assert cfg.drive_pros.max_effort == 50.0
    assert cfg.drive_pros.damping["(NECK1|NECK2)"] == 1e3


def test_solver_cfg_patch_keeps_defaults() -> None:
    tcp = [[1, 0, 0, 0.012], [0, 1, 0, 0.04], [0, 0, 1, 0.11], [0, 0, 0, 1]]
    cfg = DexforceW1Cfg.from_dict({"solver_cfg": {"left_arm": {"tcp": tcp}}})
    assert cfg.solver_cfg["left_arm"].tcp == tcp
    assert cfg.solver_cfg["left_arm"].root_link_name == "left_arm_base"
    assert cfg.solver_cfg["right_arm"].tcp[1][3] == -0.0675


@pytest.mark.parametrize("cls", [DexforceW1Cfg, SevenDofArmCfg])
def test_to_dict_round_trip(cls: type) -> None:
    cfg = cls.from_dict({"uid": "r"})
    assert cls.from_dict(cfg.to_dict()) == cfg


def test_registry_lookup_by_robot_type() -> None:
    assert type(RobotCfg.from_dict({"robot_type": "DexforceW1", "init_pos": [0, 1, 0]})) is DexforceW1Cfg
    assert type(RobotCfg.from_dict({"class_type": "SevenDofArm", "uid": "arm"})) is SevenDofArmCfg
    assert type(RobotCfg.from_dict({"class_type": "SevenDofArmCfg"})) is SevenDofArmCfg


def test_arm_defaults() -> None:
    cfg = SevenDofArmCfg()
    assert cfg.control_parts == {"arm": ["joint[1-7]"], "eef": ["finger_joint[12]"]}
    assert len(cfg.init_qpos) == 9
    assert cfg.solver_cfg["arm"].end_link_name == "hand"


def test_a_user_pattern_overrides_the_default_group_it_overlaps() -> None:
    from embodichain_core.sim.scene_build.drive_values import joint_value

    cfg = DexforceW1Cfg.from_dict({"drive_pros": {"stiffness": {"(LEFT|RIGHT)_FINGER[12]": 3000.0}}})
    stiffness = cfg.drive_pros.stiffness
    # the hand group also matches LEFT_FINGER1 (at 1e2): narrowed, it no longer does
    assert joint_value(stiffness, "LEFT_FINGER1", "drive_pros.stiffness") == 3000.0
    assert joint_value(stiffness, "LEFT_HAND_INDEX", "drive_pros.stiffness") == 1e2
    assert joint_value(stiffness, "RIGHT_J3", "drive_pros.stiffness") == 1e4
    again = DexforceW1Cfg.from_dict(cfg.to_dict())  # the merge is idempotent
    assert again.drive_pros.stiffness == stiffness
