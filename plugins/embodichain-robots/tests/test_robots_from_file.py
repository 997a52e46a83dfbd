"""Bring your own robot: URDF/MJCF arms written by the test, loaded from a JSON gym config
alone, with ``DLSSolver`` from ``solver_cfg``: IK of FK of random configurations,
``EefPoseTerm`` reaching a target, ``randomize_robot_eef_pose`` at reset, per-env damping."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import Any, Dict, List, Optional

import pytest
import torch

sys.path.append(str(Path(__file__).resolve().parents[3] / "tests"))  # the core tests' robot files

from robot_files import ARM_JOINT_NAMES, HOME, urdf_robot_section, write_mjcf_arm, write_urdf_arm  # noqa: E402

from embodichain_core.config.errors import ConfigError  # noqa: E402
from embodichain_core.config.loader import load_gym_config  # noqa: E402
from embodichain_core.envs.embodied_env import EmbodiedEnv  # noqa: E402
from embodichain_core.plugins import hookimpl, isolated_plugins, register_plugin  # noqa: E402
from embodichain_core.sim.cfg import JointDrivePropertiesCfg, RobotCfg  # noqa: E402
from embodichain_core.sim.scene_build.import_checks import ModelImportWarning  # noqa: E402
from embodichain_core.utils.configclass import configclass  # noqa: E402
from embodichain_core.utils.math import matrix_to_pose  # noqa: E402

TCP = [[1, 0, 0, 0], [0, 1, 0, 0.08], [0, 0, 1, 0], [0, 0, 0, 1]]
SOLVER = {"class_type": "DLSSolver", "root_link_name": "base_link", "end_link_name": "flange", "tcp": TCP}
EEF_EVENT = {
    "func": "randomize_robot_eef_pose",
    "mode": "reset",
    "params": {
        "entity_cfg": {"uid": "arm", "control_parts": ["arm"]},
        "position_range": [[-0.03, -0.03, -0.03], [0.03, 0.03, 0.03]],
    },
}


def gym_config(tmp_path: Path, robot: dict, actions: dict | None = None, events: dict | None = None) -> Path:
    """A JSON gym config next to the robot files (``fpath`` relative to it)."""
    data = {
        "id": "OwnRobot-v0",
        "num_envs": 4,
        "max_episode_steps": 50,
        "headless": True,
        "env": {
            "control_parts": ["arm"],
            "events": events or {},
            "actions": actions or {"eef": {"func": "EefPoseTerm", "params": {"part_name": "arm"}}},
        },
        "robot": robot,
    }
    path = tmp_path / "own_robot.json"
    path.write_text(json.dumps(data))
    return path


def make_env(path: Path) -> EmbodiedEnv:
    _, cfg, _ = load_gym_config(path)
    return EmbodiedEnv(cfg)


@pytest.fixture
def urdf_env(tmp_path: Path) -> Any:
    write_urdf_arm(tmp_path, unbalanced=True)
    robot = urdf_robot_section(Path("test_arm/urdf/arm.urdf"), solver_cfg={"arm": SOLVER})
    with pytest.warns(ModelImportWarning, match="'forearm'"):
        env = make_env(gym_config(tmp_path, robot))
    yield env
    env.close()


def test_urdf_arm_from_json_holds_its_pose(urdf_env) -> None:
    urdf_env.reset()
    robot = urdf_env.robot
    assert robot.joint_names[:6] == ARM_JOINT_NAMES
    start = robot.get_qpos().clone()
    hold = urdf_env.robot.get_qpos(target=True)[:, :6]
    for _ in range(100):
        urdf_env.sim.step(1)
    assert torch.allclose(start[:, :6], torch.tensor(HOME).expand(4, 6), atol=1e-6)
    assert (robot.get_qpos() - start).abs().max() < 1e-3
    assert torch.allclose(robot.get_qpos(target=True)[:, :6], hold)


def test_ik_of_fk_of_random_configurations(urdf_env) -> None:
    robot, solver = urdf_env.robot, urdf_env.robot.get_solver("arm")
    gen = torch.Generator().manual_seed(0)
    limits = robot.get_qpos_limits()[0, :6].clamp(-3.0, 3.0).double()
    q = limits[:, 0] + (limits[:, 1] - limits[:, 0]) * torch.rand(200, 6, generator=gen, dtype=torch.float64)
    target = solver.get_fk(q)
    seed = torch.tensor(HOME, dtype=torch.float64).expand(200, 6)
    ok, sol = solver.get_ik(target, qpos_seed=seed)
    pos_err, rot_err = solver.pose_error(target, sol)
    good = (pos_err < 1e-3) & (rot_err < 0.01)
    assert good.float().mean() >= 0.95
    assert ok[good].float().mean() >= 0.95
    lo, hi = solver.qpos_limits[:, 0], solver.qpos_limits[:, 1]
    assert ((sol >= lo - 1e-9) & (sol <= hi + 1e-9)).all()


def test_eef_pose_term_reaches_a_target(urdf_env) -> None:
    urdf_env.reset()
    robot = urdf_env.robot
    gen = torch.Generator().manual_seed(1)
    goal_q = torch.tensor(HOME) + 0.3 * (torch.rand(4, 6, generator=gen) - 0.5)  # reachable by construction
    target = robot.compute_fk(goal_q, name="arm")
    start = robot.compute_fk(name="arm")
    assert (start[:, :3, 3] - target[:, :3, 3]).norm(dim=-1).min() > 0.02
    action = matrix_to_pose(target).float()
    assert urdf_env.action_manager.process_action(action)["ik_success"].all()
    for _ in range(25):
        urdf_env.step(action)
    reached = robot.compute_fk(name="arm")
    assert (reached[:, :3, 3] - target[:, :3, 3]).norm(dim=-1).max() < 2e-3
    assert torch.allclose(reached[:, :3, :3], target[:, :3, :3], atol=0.01)


def test_randomize_eef_pose_at_reset_from_json(tmp_path: Path) -> None:
    write_urdf_arm(tmp_path)
    robot = urdf_robot_section(Path("test_arm/urdf/arm.urdf"), solver_cfg={"arm": SOLVER})
    env = make_env(gym_config(tmp_path, robot, events={"eef": EEF_EVENT}))
    try:
        env.reset(seed=3)
        pose = env.robot.compute_fk(name="arm")
        home = env.robot.compute_fk(torch.tensor(HOME).expand(4, 6), name="arm")
        offset = (pose[:, :3, 3] - home[:, :3, 3]).abs()
        assert (offset.amax(-1) > 1e-3).all()  # moved in every env
        assert (offset <= 0.03 + 1e-3).all()  # within the range
        assert len({round(float(v), 6) for v in offset[:, 0]}) == 4  # a different draw per env
    finally:
        env.close()


def test_per_env_damping_differs_across_envs(urdf_env) -> None:
    robot = urdf_env.robot
    robot.set_joint_damping(torch.tensor([1.0, 2.0, 4.0, 8.0])[:, None], joint_ids=robot.get_joint_ids("arm"))
    damping = robot.get_joint_damping(joint_ids=robot.get_joint_ids("arm"))
    assert torch.allclose(damping[:, 3], torch.tensor([1.0, 2.0, 4.0, 8.0]))
    assert len(set(damping[:, 0].tolist())) == 4


@pytest.mark.parametrize(
    "solver, key, needle",
    [
        ({**SOLVER, "end_link_name": "flang"}, "robot.solver_cfg.arm.end_link_name", "'flange'"),
        (
            {**SOLVER, "root_link_name": "flange", "end_link_name": "base_link"},
            "robot.solver_cfg.arm.end_link_name",
            "not a descendant",
        ),
        ({**SOLVER, "root_link_name": "shoulder"}, "robot.solver_cfg.arm", "'shoulder_pan'"),
        ({**SOLVER, "class_type": "DLSSolve"}, "robot.solver_cfg.arm.class_type", "'DLSSolver'"),
        ({**SOLVER, "max_iteration": 3}, "robot.solver_cfg.arm.max_iteration", "max_iterations"),
    ],
)
def test_bad_solver_cfg_names_the_key(tmp_path: Path, solver: dict, key: str, needle: str) -> None:
    write_urdf_arm(tmp_path)
    robot = urdf_robot_section(Path("test_arm/urdf/arm.urdf"), solver_cfg={"arm": solver})
    with pytest.raises(ConfigError) as err:
        make_env(gym_config(tmp_path, robot))
    assert key in str(err.value)
    assert needle in str(err.value)


def test_mjcf_arm_with_its_own_actuators_from_json(tmp_path: Path) -> None:
    write_mjcf_arm(tmp_path)
    robot = {
        "uid": "arm",
        "fpath": "servo_arm.xml",
        "keep_actuators": True,
        "init_qpos": [0.3, 0.5, -0.4],
        "control_parts": {"arm": ["j[1-3]"]},
    }
    actions = {"qpos": {"func": "QposTerm", "params": {}}}
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelImportWarning)  # kept: no replacement notice
        env = make_env(gym_config(tmp_path, robot, actions=actions))
    try:
        env.reset()
        start = env.robot.get_qpos().clone()
        for _ in range(100):
            env.sim.step(1)
        assert (env.robot.get_qpos() - start).abs().max() < 1e-3
        for _ in range(40):
            env.step(torch.tensor([[0.0, 0.2, 0.1]]).expand(4, 3))
        assert torch.allclose(env.robot.get_qpos(), torch.tensor([0.0, 0.2, 0.1]).expand(4, 3), atol=0.02)
        assert env.sim.ctrl[0, 0] == 0.0
        assert float(env.sim.ctrl[0, 1]) == pytest.approx(0.2)
    finally:
        env.close()


@configclass
class FileArmCfg(RobotCfg):
    """A file-based robot with defaults, as a plugin would ship it (docs/robots.md, section 6.5)."""

    fpath: Optional[str] = "test_arm/urdf/arm.urdf"
    init_qpos: Optional[List[float]] = HOME + [0.01, 0.01]
    control_parts: Optional[Dict[str, List[str]]] = {"arm": ARM_JOINT_NAMES}
    drive_pros: JointDrivePropertiesCfg = JointDrivePropertiesCfg(stiffness=2000.0, damping=100.0, armature=0.05)
    solver_cfg: Optional[Any] = {"arm": SOLVER}


def test_a_plugin_registers_a_file_based_robot_with_its_assets(tmp_path: Path) -> None:
    data = tmp_path / "data"
    write_urdf_arm(data)

    class FileArmPlugin:
        @hookimpl
        def embodichain_register_assets(self, register) -> None:
            register("embodichain-filearm", data)

        @hookimpl
        def embodichain_register_robots(self, register) -> None:
            register("FileArm", FileArmCfg)

    with isolated_plugins(load_entry_points=True):
        register_plugin(FileArmPlugin(), name="embodichain-filearm")
        env = make_env(gym_config(tmp_path, {"class_type": "FileArm", "uid": "arm"}))
        try:
            env.reset()
            assert isinstance(env.robot.cfg, FileArmCfg)
            assert env.robot.get_solver("arm").joint_ids == list(range(6))
            goal = env.robot.compute_fk(
                torch.tensor(HOME) + torch.tensor([0.1, -0.1, 0.1, 0.1, -0.1, 0.1]), name="arm"
            ).expand(4, 4, 4)
            assert (env.robot.compute_fk(name="arm")[:, :3, 3] - goal[:, :3, 3]).norm(dim=-1).min() > 0.02
            assert eef_term_reaches(env, goal)
        finally:
            env.close()


def eef_term_reaches(env: EmbodiedEnv, target: torch.Tensor) -> bool:
    """Step ``EefPoseTerm`` toward ``target`` (4, 4, 4) and report whether the TCP is within 2 mm."""
    for _ in range(25):
        env.step(matrix_to_pose(target).float())
    return bool((env.robot.compute_fk(name="arm")[:, :3, 3] - target[:, :3, 3]).norm(dim=-1).max() < 2e-3)


def test_mjdls_solver_from_json_agrees_with_dls(tmp_path: Path, urdf_env) -> None:
    write_urdf_arm(tmp_path)
    solver = {**SOLVER, "class_type": "embodichain-robots/MjDLSSolver"}
    env = make_env(gym_config(tmp_path, urdf_robot_section(Path("test_arm/urdf/arm.urdf"), solver_cfg={"arm": solver})))
    try:
        assert type(env.robot.get_solver("arm")).__name__ == "MjDLSSolver"
        q = torch.tensor(HOME, dtype=torch.float64) + torch.linspace(-0.2, 0.2, 6, dtype=torch.float64)
        mj_pose = env.robot.get_solver("arm").get_fk(q[None])
        assert torch.allclose(mj_pose, urdf_env.robot.get_solver("arm").get_fk(q[None]), atol=1e-9)
    finally:
        env.close()
