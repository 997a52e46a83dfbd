"""Part forward kinematics where the sim's tensors are: parity with the host path (the
chain's ``forward`` product after a CPU copy) and MuJoCo, no host copy or sync (a sim on
the ``meta`` device: every copy to the host or value read raises there), and the per-part
cache of the current pose (never stale after a state write, a step, a reset or a TCP change)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest
import torch

from embodichain_core.sim.cfg import SimulationManagerCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.utils.math import pose_to_matrix
from embodichain_robots.kinematics.solver import sample_joint_values
from embodichain_robots.seven_dof_arm.cfg import SevenDofArmCfg

PARTS = {"w1": [("left_arm", "left_tcp"), ("right_arm", "right_tcp")], "arm": [("arm", "tcp")]}


@pytest.fixture(scope="module")
def floating() -> Any:
    """The 7-DoF arm on a free joint (three envs)."""
    scene = Scene(SimulationManagerCfg(), num_envs=3)
    scene.add_robot(SevenDofArmCfg.from_dict({"uid": "arm", "fix_base": False}))
    scene.build()
    return scene["arm"]


def _randomize(robot: Any, seed: int) -> None:
    """Random joint values (and a random root pose when the base floats), forward run."""
    gen = torch.Generator().manual_seed(seed)
    for part in robot.solvers:
        solver = robot.get_solver(part)
        q = sample_joint_values(solver.qpos_limits, robot.num_envs, gen)
        robot.set_qpos(q, joint_ids=solver.joint_ids, target=False)
    if robot.is_floating:
        quat = torch.randn(robot.num_envs, 4, generator=gen, dtype=torch.float64)
        pos = torch.rand(robot.num_envs, 3, generator=gen, dtype=torch.float64)
        robot.set_local_pose(torch.cat((pos, quat / quat.norm(dim=-1, keepdim=True)), -1))
    robot.sim.forward()


def _host_fk(robot: Any, part: str) -> torch.Tensor:
    """The host path: CPU float64 copies of the joint values and root link pose, the chain's
    ``forward`` product (joint frames and all), the root pose times it."""
    solver = robot.get_solver(part)
    q = robot.sim.qpos[:, robot.qpos_adr[solver.joint_ids]].to("cpu", torch.float64)
    body = int(robot.body_ids[robot.find_bodies(solver.root_link_name)[0][0]])
    root = torch.cat((robot.sim.xpos[:, body], robot.sim.xquat[:, body]), -1).to("cpu", torch.float64)
    return pose_to_matrix(root) @ solver.chain.forward(q, solver.tcp)[0]


def _site(robot: Any, site: str) -> tuple[torch.Tensor, torch.Tensor]:
    sid = robot.scene.model.site(f"{robot.uid}/{site}").id
    return robot.sim.site_xpos[:, sid], robot.sim.site_xmat[:, sid].reshape(-1, 3, 3)


@pytest.mark.parametrize("which", ["w1", "arm", "floating"])
def test_part_fk_matches_the_host_path_and_mujoco(which: str, request: pytest.FixtureRequest) -> None:
    robot = request.getfixturevalue(which)
    for seed in range(3):
        _randomize(robot, seed)
        for part, site in PARTS["w1" if which == "w1" else "arm"]:
            pose64 = robot._part_fk64(part, None, None)
            assert torch.equal(pose64, _host_fk(robot, part))  # float64 parity, bit for bit
            pose = robot.compute_fk(name=part)
            assert torch.equal(pose, pose64.float())
            pos, mat = _site(robot, site)
            assert torch.allclose(pose64[:, :3, 3], pos.double(), atol=1e-9)
            assert torch.allclose(pose64[:, :3, :3], mat.double(), atol=1e-9)


def test_solver_fk_matches_the_joint_frame_product(w1: Any) -> None:
    solver = w1.get_solver("left_arm")
    q = sample_joint_values(solver.qpos_limits, 50, torch.Generator().manual_seed(4))
    assert torch.equal(solver.get_fk(q), solver.chain.forward(q, solver.tcp)[0])
    assert torch.equal(solver.get_fk(q.float()), solver.chain.forward(q.float(), solver.tcp)[0])


class _MetaScene:
    """The robot's scene with its sim's views on the ``meta`` device (no data: any host copy,
    ``.item()`` or ``bool()`` of them raises), everything else from the real scene."""

    def __init__(self, scene: Any):
        self._scene, sim = scene, scene.sim
        views = {k: getattr(sim, k).to("meta") for k in ("qpos", "xpos", "xquat")}
        self.sim = SimpleNamespace(device=torch.device("meta"), **views)
        self.device = torch.device("meta")

    def __getattr__(self, name: str) -> Any:
        return getattr(self._scene, name)


def test_part_fk_stays_on_the_sim_device(w1: Any, arm: Any, floating: Any) -> None:
    with pytest.raises(NotImplementedError):
        torch.zeros(2, device="meta").cpu()  # the stand-in refuses host copies
    for robot in (w1, arm, floating):
        scene = robot.scene
        robot.scene = _MetaScene(scene)
        try:
            for part in robot.solvers:
                pose = robot.compute_fk(name=part)
                assert pose.device.type == "meta"
                assert pose.shape == (robot.num_envs, 4, 4)
                assert robot.compute_fk(name=part, to_matrix=False).shape == (robot.num_envs, 7)
        finally:
            robot.scene = scene


def _counting(solver: Any) -> list[int]:
    calls = [0]
    inner = type(solver).get_fk

    def get_fk(qpos: torch.Tensor) -> torch.Tensor:
        calls[0] += 1
        return inner(solver, qpos)

    solver.get_fk = get_fk
    return calls


def test_the_current_pose_is_computed_once_and_never_stale(floating: Any) -> None:
    robot, solver = floating, floating.get_solver("arm")
    calls = _counting(solver)
    try:
        _randomize(robot, 7)
        first = robot.compute_fk(name="arm")
        first[:] = 0.0  # a caller's in-place edit does not reach the cache
        again = robot.compute_fk(name="arm", to_matrix=False)
        assert calls[0] == 1
        assert torch.allclose(again[:, :3], _site(robot, "tcp")[0].float())
        changes = {
            "state write": lambda: _randomize(robot, 8),
            "root pose": lambda: (robot.set_local_pose([[0.1, 0.2, 0.3, 1.0, 0.0, 0.0, 0.0]] * 3), robot.sim.forward()),
            "step": lambda: robot.sim.step(5),
            "reset": lambda: (robot.scene.reset(), robot.sim.forward()),
        }
        for what, change in changes.items():
            before = calls[0]
            change()
            pose = robot.compute_fk(name="arm")
            assert calls[0] == before + 1, what
            assert torch.allclose(pose[:, :3, 3], _site(robot, "tcp")[0].float(), atol=1e-5), what
        tcp = solver.get_tcp()
        solver.set_tcp(torch.eye(4, dtype=torch.float64))
        flange = robot.compute_fk(name="arm")
        solver.set_tcp(tcp)
        assert not torch.allclose(flange, robot.compute_fk(name="arm"))
        robot.compute_fk(qpos=torch.zeros(3, 7), name="arm")  # explicit joint values: never cached
        assert torch.allclose(robot.compute_fk(name="arm")[:, :3, 3], _site(robot, "tcp")[0].float(), atol=1e-5)
    finally:
        del solver.get_fk
