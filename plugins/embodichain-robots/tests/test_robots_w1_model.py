"""W1 acceptance checks (reference section 8.9) on the procedural model."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import torch

from embodichain_robots.dexforce_w1 import params as P
from embodichain_robots.dexforce_w1.cfg import DexforceW1Cfg
from embodichain_robots.kinematics.dh import w1_arm_dh_fk

LEFT_EE = [[1, 0, 0, 0], [0, 0, 1, 0.791], [0, -1, 0, 1.3648], [0, 0, 0, 1]]
RIGHT_EE = [[1, 0, 0, 0], [0, 0, -1, -0.791], [0, 1, 0, 1.3648], [0, 0, 0, 1]]
#: ScoopIce's init_qpos (EmbodiChain configs/gym/scoop_ice/gym_config.json), BFS order.
SCOOP_QPOS = [
    0.42241,
    -1.11061,
    0.55116,
    0.01815,
    0.00002,
    -0.43273,
    -0.30339,
    0.2412,
    -1.20074,
    0.72621,
    0.40264,
    -0.41044,
    -1.34341,
    1.27664,
    -0.42869,
    -0.30873,
    -0.23608,
    0.54272,
    -0.12095,
    -0.16959,
    0.00011,
    0.00002,
    0.00009,
    0.00003,
    1.50006,
    0.30045,
    0.30028,
    0.30051,
    0.30037,
    0.90003,
    0.23262,
    0.24298,
    0.22003,
    0.19901,
    0.0,
    0.59305,
    0.6033,
    0.58056,
    0.55942,
    0.29999,
]


def _model(**cfg: object) -> mujoco.MjModel:
    return DexforceW1Cfg.from_dict({"uid": "w1", **cfg}).build_spec().compile()


def _pose(model: mujoco.MjModel, data: mujoco.MjData, body: str) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = data.xmat[model.body(body).id].reshape(3, 3)
    out[:3, 3] = data.xpos[model.body(body).id]
    return out


def _at(q: dict[str, float], **cfg: object) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = _model(**cfg)
    data = mujoco.MjData(model)
    for name, value in q.items():
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)
    return model, data


def test_zero_pose_flanges_and_arm_base(w1: object) -> None:
    ee = w1.compute_fk(torch.zeros(2, 40), link_names=["left_ee", "right_ee"])
    assert torch.allclose(ee[:, 0], torch.tensor(LEFT_EE, dtype=torch.float32), atol=1e-5)
    assert torch.allclose(ee[:, 1], torch.tensor(RIGHT_EE, dtype=torch.float32), atol=1e-5)
    for side, sign in (("left", 1), ("right", -1)):
        base = w1.get_link_pose(f"{side}_arm_base")[0]
        assert torch.allclose(base[:3], torch.tensor([0.0, sign * 0.0985, 1.3648]), atol=1e-6)
        assert torch.allclose(base[3:], torch.tensor(P.ARM_BASE_QUAT[side], dtype=torch.float32), atol=1e-6)


def test_mirror_example() -> None:
    left = dict(zip([f"LEFT_J{i}" for i in range(1, 8)], (0, -math.pi / 4, 0, -math.pi / 2, -math.pi / 4, 0, 0)))
    right = dict(zip([f"RIGHT_J{i}" for i in range(1, 8)], (0, math.pi / 4, 0, math.pi / 2, math.pi / 4, 0, 0)))
    model, data = _at({**left, **right})
    assert np.allclose(_pose(model, data, "left_ee")[:3, 3], [0.33, 0.3848, 1.181], atol=5e-4)
    assert np.allclose(_pose(model, data, "right_ee")[:3, 3], [0.33, -0.3848, 1.181], atol=5e-4)
    mirror = np.diag([1.0, -1.0, 1.0])
    assert np.allclose(mirror @ _pose(model, data, "left_ee")[:3, 3], _pose(model, data, "right_ee")[:3, 3])


@pytest.mark.parametrize("arm_kind", ["anthropomorphic", "industrial"])
def test_arm_matches_dh_fk(arm_kind: str) -> None:
    model = _model(arm_kind=arm_kind)
    data = mujoco.MjData(model)
    qs = np.random.default_rng(0).uniform(-2.5, 2.5, (100, 7))
    for side in P.SIDES:
        adr = [model.joint(f"{side.upper()}_J{i}").qposadr[0] for i in range(1, 8)]
        dh = w1_arm_dh_fk(torch.as_tensor(qs), side, arm_kind).numpy()
        for k, q in enumerate(qs):
            data.qpos[adr] = q
            mujoco.mj_kinematics(model, data)
            rel = np.linalg.inv(_pose(model, data, f"{side}_arm_base")) @ _pose(model, data, f"{side}_ee")
            assert np.abs(rel - dh[k]).max() < 1e-12


def test_scoop_ice_pose(scene_factory: object) -> None:
    robot = scene_factory(DexforceW1Cfg.from_dict({"uid": "w1", "init_qpos": SCOOP_QPOS}), num_envs=1)["w1"]
    right, left = robot.compute_fk(name="right_arm")[0], robot.compute_fk(name="left_arm")[0]
    assert torch.allclose(right[:3, 3], torch.tensor([0.555, -0.252, 0.927]), atol=2e-3)
    assert right[2, 2] < -0.85  # approach axis points down
    assert torch.allclose(left[:3, 3], torch.tensor([0.574, 0.094, 0.987]), atol=2e-3)
    eyes = robot.get_link_pose("eyes", to_matrix=True)[0]
    assert torch.allclose(eyes[:3, 3], torch.tensor([0.262, 0.0, 1.404]), atol=3e-3)
    look = -eyes[:3, 2]
    assert math.degrees(math.asin(-float(look[2]))) == pytest.approx(48.0, abs=1.0)


def test_crouch_keeps_torso_upright() -> None:
    model, data = _at({"ANKLE": 1.0, "KNEE": -2.0, "BUTTOCK": 1.0})
    assert _pose(model, data, "left_arm_base")[2, 3] == pytest.approx(1.061, abs=1e-3)
    assert np.allclose(_pose(model, data, "waist")[:3, :3], np.eye(3), atol=1e-12)


def test_eyes_frame_and_stereo_cameras() -> None:
    model, data = _at({})
    eyes = _pose(model, data, "eyes")
    assert np.allclose(eyes[:3, 3], [0.091, 0.0, 1.571], atol=1e-9)
    assert np.allclose(eyes[:3, 0], [0, -1, 0], atol=1e-4)  # image right = robot right
    assert np.allclose(eyes[:3, 1], [0.25959, 0, 0.96572], atol=1e-4)  # up
    assert math.degrees(math.asin(eyes[2, 2])) == pytest.approx(15.0, abs=0.05)  # looks 15 deg down
    left, right = (model.camera(f"eyes_{s}") for s in ("left", "right"))
    assert np.allclose(right.pos - left.pos, [P.STEREO_BASELINE, 0, 0])
    assert float(left.fovy[0]) == pytest.approx(61.93, abs=0.01)
    for side in P.SIDES:
        assert model.camera(f"{side}_wrist_camera").bodyid == model.body(f"{side}_wrist_camera").id


@pytest.mark.parametrize(
    ("cfg", "dof", "mimic"),
    [
        ({}, 40, 8),
        ({"arm_kind": "industrial"}, 24, 0),
        ({"hand_types": {"left": "dh_pgc_gripper", "right": "DH_PGC_GRIPPER_M"}}, 24, 0),
        ({"with_default_eef": False}, 20, 0),
        ({"hand_types": {"left": "BRAINCO_HAND"}}, 30, 4),
    ],
)
def test_dof_counts(cfg: dict, dof: int, mimic: int) -> None:
    model = _model(**cfg)
    assert model.njnt == dof
    assert model.neq == mimic


def test_part_joint_ids(w1: object) -> None:
    assert w1.dof == 40
    assert w1.get_joint_ids("left_arm") == [6, 8, 10, 12, 14, 16, 18]
    assert w1.get_joint_ids("right_arm") == [7, 9, 11, 13, 15, 17, 19]
    assert w1.get_joint_ids("torso") == [0, 1, 2, 3]
    assert w1.get_joint_ids("head") == [4, 5]
    assert w1.get_joint_ids("dual_arm") == list(range(6, 20, 2)) + list(range(7, 20, 2))
    assert w1.get_joint_ids("full_body") == [0, 1, 2, 3, 4, 5] + list(range(6, 20, 2)) + list(range(7, 20, 2))
    assert len(w1.mimic_ids) == 8
    assert len(w1.get_joint_ids("left_eef")) == 6
    assert sorted(w1.get_joint_ids("left_eef")) == [20, 21, 22, 23, 24, 34]
    assert w1.joint_names[24] == "LEFT_HAND_THUMB2"
    assert w1.joint_names[29] == "RIGHT_HAND_THUMB2"
    assert set(w1.control_parts) == {
        "torso",
        "head",
        "left_arm",
        "right_arm",
        "dual_arm",
        "left_eef",
        "right_eef",
        "full_body",
    }


def test_mimic_joints_follow(w1: object) -> None:
    pip, parent = w1.joint_names.index("LEFT_INDEX_PIP"), w1.joint_names.index("LEFT_HAND_INDEX")
    assert w1.mimic_parents[w1.mimic_ids.index(pip)] == parent
    q = w1.get_qpos().clone()
    q[:, parent] = 0.8
    w1.set_qpos(q, target=False)
    assert torch.allclose(w1.get_qpos()[:, pip], torch.full((2,), 0.8))
    w1.reset()


def test_v025_flange_offset_moves_hand_and_tcp() -> None:
    base, v25 = _at({}), _at({}, version="v025")
    for side in P.SIDES:
        shift = _pose(*v25, f"{side}_hand_base")[:3, 3] - _pose(*base, f"{side}_hand_base")[:3, 3]
        ee_z = _pose(*base, f"{side}_ee")[:3, 2]
        assert np.allclose(shift, 0.012 * ee_z, atol=1e-12)
    tcp = np.asarray(DexforceW1Cfg.from_dict({"version": "v025"}).solver_cfg["left_arm"].tcp)
    assert tcp[2, 3] == pytest.approx(0.127 + 0.012)


def test_industrial_limits_and_gripper() -> None:
    cfg = DexforceW1Cfg.from_dict({"uid": "w1", "arm_kind": "industrial"})
    model = cfg.build_spec().compile()
    assert np.allclose(np.degrees(model.joint("LEFT_J6").range), [-90, 90])
    assert np.allclose(np.degrees(model.joint("LEFT_J7").range), [-170, 170])
    assert cfg.control_parts["left_eef"] == ["LEFT_FINGER1", "LEFT_FINGER2"]
    assert np.asarray(cfg.solver_cfg["right_arm"].tcp)[2, 3] == pytest.approx(0.15)
