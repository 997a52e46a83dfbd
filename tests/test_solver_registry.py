"""Solvers from ``solver_cfg`` of a plain robot section, through the solver registry: a
fixture plugin registers a solver (MuJoCo FK/Jacobian, damped least squares); names
resolve bare, qualified and with suggestions; bad parts, links and chains are config
errors at their keys."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest
import torch
from robot_files import ARM_JOINT_NAMES, urdf_robot_section, write_urdf_arm

from embodichain_core.config.errors import ConfigError
from embodichain_core.plugins import get_solver_class, hookimpl, isolated_plugins, register_plugin, solver_registry
from embodichain_core.sim.cfg import RobotCfg, SimulationManagerCfg
from embodichain_core.sim.scene import Scene


class FixtureSolver:
    """FK and damped-least-squares IK of a chain on MuJoCo's own kinematics (env-agnostic)."""

    def __init__(self, robot: Any, root: str, end: str, joint_ids: list[int]):
        self.model, self.data = robot.scene.model, mujoco.MjData(robot.scene.model)
        self.root_link_name = root
        self.root, self.end = (self.model.body(f"{robot.uid}/{n}").id for n in (root, end))
        self.joint_ids = joint_ids
        self.adr = robot.qpos_adr.numpy()[joint_ids]
        self.dof = robot.dof_adr.numpy()[joint_ids]

    @classmethod
    def from_config(cls, cfg: dict, robot: Any, part: str) -> "FixtureSolver":
        if cfg.get("tcp") is not None:
            raise ConfigError("tcp", "the fixture solver has no TCP")
        joints = cfg.get("joints", robot.get_joint_ids(part, remove_mimic=True))
        return cls(robot, cfg["root_link_name"], cfg["end_link_name"], list(joints))

    def _pose_jac(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = self.data
        d.qpos[self.adr] = q
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_comPos(self.model, d)
        jacp, jacr = np.zeros((3, self.model.nv)), np.zeros((3, self.model.nv))
        mujoco.mj_jacBody(self.model, d, jacp, jacr, self.end)
        rot0 = d.xmat[self.root].reshape(3, 3)
        pose = np.eye(4)
        pose[:3, :3] = rot0.T @ d.xmat[self.end].reshape(3, 3)
        pose[:3, 3] = rot0.T @ (d.xpos[self.end] - d.xpos[self.root])
        return pose, np.vstack((rot0.T @ jacp[:, self.dof], rot0.T @ jacr[:, self.dof]))

    def get_fk(self, qpos: torch.Tensor) -> torch.Tensor:
        return torch.as_tensor(np.stack([self._pose_jac(q)[0] for q in np.asarray(qpos)]))

    def get_ik(self, target: torch.Tensor, qpos_seed: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        out, ok = torch.as_tensor(qpos_seed, dtype=torch.float64).numpy().copy(), []
        for k, goal in enumerate(np.asarray(target)):
            for _ in range(100):
                pose, jac = self._pose_jac(out[k])
                rot_err = 0.5 * np.cross(pose[:3, :3], goal[:3, :3], axis=0).sum(-1)
                err = np.concatenate((goal[:3, 3] - pose[:3, 3], rot_err))
                out[k] += jac.T @ np.linalg.solve(jac @ jac.T + 1e-6 * np.eye(6), err)
            ok.append(bool(np.linalg.norm(err) < 1e-4))
        return torch.tensor(ok), torch.as_tensor(out)


class FixtureSolverPlugin:
    @hookimpl
    def embodichain_register_solvers(self, register) -> None:
        register("FixtureSolver", FixtureSolver)


ARM_SOLVER = {"class_type": "FixtureSolver", "root_link_name": "base_link", "end_link_name": "flange"}


@pytest.fixture
def solvers():
    with isolated_plugins():
        register_plugin(FixtureSolverPlugin(), name="fixture-solvers")
        yield


def robot_of(tmp_path: Path, solver_cfg: Any, num_envs: int = 2) -> Any:
    section = json.loads(json.dumps(urdf_robot_section(write_urdf_arm(tmp_path), solver_cfg=solver_cfg)))
    scene = Scene(SimulationManagerCfg(), num_envs=num_envs)
    scene.add_robot(RobotCfg.from_dict(section))
    scene.build()
    return scene["arm"]


def test_names_resolve_bare_qualified_and_ignoring_case(solvers) -> None:
    assert get_solver_class("FixtureSolver") is FixtureSolver
    assert get_solver_class("fixture-solvers/FixtureSolver") is FixtureSolver
    assert get_solver_class("fixturesolver") is FixtureSolver
    assert solver_registry().names() == ["FixtureSolver"]


def test_solver_cfg_of_a_plain_robot_builds_the_part_solver(solvers, tmp_path: Path) -> None:
    robot = robot_of(tmp_path, {"arm": ARM_SOLVER})
    assert isinstance(robot.get_solver("arm"), FixtureSolver)
    assert robot.get_solver("arm").joint_ids == [0, 1, 2, 3, 4, 5]
    flange = robot.get_link_pose("flange", to_matrix=True)
    assert torch.allclose(robot.compute_fk(name="arm"), flange, atol=1e-5)
    target = flange.clone()
    target[:, 2, 3] -= 0.05
    ok, q = robot.compute_ik(target, name="arm")
    assert ok.all()
    assert torch.allclose(robot.compute_fk(q, name="arm"), target, atol=1e-4)


@pytest.mark.parametrize(
    "solver_cfg, path, needle",
    [
        ({"arm": {**ARM_SOLVER, "class_type": "FixtureSolvr"}}, "robot.solver_cfg.arm.class_type", "'FixtureSolver'"),
        ({"arm": {"root_link_name": "base_link"}}, "robot.solver_cfg.arm.class_type", "FixtureSolver"),
        ({"arms": ARM_SOLVER}, "robot.solver_cfg.arms", "Did you mean 'arm'"),
        ({"arm": {**ARM_SOLVER, "end_link_name": "flang"}}, "robot.solver_cfg.arm.end_link_name", "'flange'"),
        ({"arm": {**ARM_SOLVER, "tcp": [[1, 0, 0, 0]]}}, "robot.solver_cfg.arm.tcp", "no TCP"),
        ({"arm": {**ARM_SOLVER, "joints": [0, 1, 2]}}, "robot.solver_cfg.arm", "'wrist_1'"),
        ({"arm": "DLS"}, "robot.solver_cfg.arm", "mapping"),
    ],
)
def test_bad_solver_cfg_is_a_config_error_at_its_key(solvers, tmp_path: Path, solver_cfg, path, needle) -> None:
    with pytest.raises(ConfigError) as err:
        robot_of(tmp_path, solver_cfg)
    assert err.value.path == path
    assert needle in err.value.reason


def test_no_solver_plugin_names_the_fix(tmp_path: Path) -> None:
    with isolated_plugins():
        with pytest.raises(ConfigError, match="unknown solver 'FixtureSolver'.*no solvers are registered"):
            robot_of(tmp_path, {"arm": ARM_SOLVER})


def test_a_robot_without_solver_cfg_says_how_to_add_one(solvers, tmp_path: Path) -> None:
    robot = robot_of(tmp_path, None)
    with pytest.raises(KeyError, match="solver_cfg"):
        robot.get_solver("arm")
    assert robot.joint_names[:6] == ARM_JOINT_NAMES


def test_part_and_class_type_are_checked_when_the_config_loads(solvers, tmp_path: Path) -> None:
    from embodichain_core.config.solver_check import check_solver_cfg

    section = urdf_robot_section(write_urdf_arm(tmp_path), solver_cfg={"arm": ARM_SOLVER})
    check_solver_cfg(RobotCfg.from_dict(section), "robot")  # valid: no error, nothing built
    section["solver_cfg"] = {"gripper": {"class_type": "FixtureSolver"}, "hand": ARM_SOLVER}
    with pytest.raises(ConfigError) as err:
        check_solver_cfg(RobotCfg.from_dict(section), "robot")
    assert err.value.path == "robot.solver_cfg.hand"
    section["solver_cfg"] = {"arm": {"class_type": "embodichain-robots/FixtureSolver"}}
    with pytest.raises(ConfigError, match="no plugin named 'embodichain-robots' provides solvers"):
        check_solver_cfg(RobotCfg.from_dict(section), "robot")
