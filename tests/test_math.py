"""The maths module (``embodichain_core.utils.math``) against MuJoCo's own ``mju_*`` functions.

Every function runs in four flavours on the same random batch: numpy float64, torch float64
on the CPU (computed on numpy views), torch float64 with autograd (computed by torch) and
torch float32; each result must match MuJoCo's and keep the flavour it was given.
"""

from __future__ import annotations

from typing import Any, Callable

import mujoco
import numpy as np
import pytest
import torch

from embodichain_core.utils import math as M

N = 64
FLAVOURS = ("numpy", "torch", "torch-autograd", "torch-float32")
TOL = {"numpy": 1e-12, "torch": 1e-12, "torch-autograd": 1e-12, "torch-float32": 1e-5}


def _as(flavour: str, x: np.ndarray) -> Any:
    if flavour == "numpy":
        return x.copy()
    if flavour == "torch-float32":
        return torch.tensor(x, dtype=torch.float32)
    return torch.tensor(x, dtype=torch.float64, requires_grad=flavour == "torch-autograd")


def _back(flavour: str, out: Any, float64: bool = False) -> np.ndarray:
    """``out`` as numpy, after checking it kept the input's flavour and dtype (or is float64)."""
    if flavour == "numpy":
        assert isinstance(out, np.ndarray)
        assert out.dtype == np.float64
        return out
    assert isinstance(out, torch.Tensor)
    assert out.dtype == (torch.float32 if flavour == "torch-float32" and not float64 else torch.float64)
    return out.detach().numpy().astype(np.float64)


def _mju(fn: Callable[..., None], size: int, *batches: np.ndarray, **kwargs: Any) -> np.ndarray:
    """``fn(out, *row)`` of MuJoCo for every row of ``batches``."""
    out = np.zeros((len(batches[0]), size))
    for i, row in enumerate(zip(*batches)):
        fn(out[i], *(np.ascontiguousarray(r, dtype=np.float64).reshape(-1) for r in row), **kwargs)
    return out


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


def _quats(rng: np.random.Generator, n: int = N) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _mats(quats: np.ndarray) -> np.ndarray:
    return _mju(mujoco.mju_quat2Mat, 9, quats).reshape(-1, 3, 3)


def _poses(rng: np.random.Generator, n: int = N) -> np.ndarray:
    return np.concatenate([rng.normal(size=(n, 3)), _quats(rng, n)], axis=-1)


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_quaternion_algebra_matches_mujoco(rng: np.random.Generator, flavour: str) -> None:
    a, b, v = _quats(rng), _quats(rng), rng.normal(size=(N, 3))
    tol = TOL[flavour]
    got = _back(flavour, M.quat_mul(_as(flavour, a), _as(flavour, b)))
    np.testing.assert_allclose(got, _mju(mujoco.mju_mulQuat, 4, a, b), atol=tol)
    got = _back(flavour, M.quat_conjugate(_as(flavour, a)))
    np.testing.assert_allclose(got, _mju(mujoco.mju_negQuat, 4, a), atol=tol)
    got = _back(flavour, M.quat_rotate(_as(flavour, a), _as(flavour, v)))
    np.testing.assert_allclose(got, _mju(mujoco.mju_rotVecQuat, 3, v, a), atol=tol * 10)
    scaled = a * rng.uniform(0.5, 2.0, (N, 1))
    got = _back(flavour, M.quat_normalize(_as(flavour, scaled)))
    expected = scaled.copy()
    for q in expected:
        mujoco.mju_normalize4(q)
    np.testing.assert_allclose(got, expected, atol=tol)


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_matrices_match_mujoco(rng: np.random.Generator, flavour: str) -> None:
    q = _quats(rng)
    mats = _mats(q)
    got = _back(flavour, M.quat_to_matrix(_as(flavour, q)))
    np.testing.assert_allclose(got, mats, atol=TOL[flavour])
    expected = _mju(mujoco.mju_mat2Quat, 4, mats)
    expected[expected[:, 0] < 0] *= -1  # the module's sign convention: w >= 0
    got = _back(flavour, M.matrix_to_quat(_as(flavour, mats)))
    np.testing.assert_allclose(got, expected, atol=TOL[flavour])
    assert np.all(got[:, 0] >= 0)


def test_numpy_conversions_equal_mujoco_bit_for_bit(rng: np.random.Generator) -> None:
    """Models built from matrices and Euler angles get MuJoCo's own numbers."""
    mats = _mats(_quats(rng, 2000))
    expected = _mju(mujoco.mju_mat2Quat, 4, mats)
    expected[expected[:, 0] < 0] *= -1
    np.testing.assert_array_equal(M.matrix_to_quat(mats), expected)
    euler = rng.uniform(-180.0, 180.0, (2000, 3))
    expected = _mju(mujoco.mju_euler2Quat, 4, np.radians(euler), seq="XYZ")
    np.testing.assert_array_equal(M.euler_xyz_to_quat(euler), expected)


HALF_TURN_AXES = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -1, 0), (0, 1, -1), (1, 1, 1), (-1, 2, 3)]


@pytest.mark.parametrize("angle", [180.0, 179.9999, -180.0])
@pytest.mark.parametrize("axis", HALF_TURN_AXES)
def test_half_turns_and_near_half_turns(axis: tuple[int, ...], angle: float) -> None:
    """w = 0 (or nearly): the branch MuJoCo takes decides the sign of x, y, z; ties included."""
    unit = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, unit, np.radians(angle))
    mat = _mats(q[None])[0]
    expected = np.zeros(4)
    mujoco.mju_mat2Quat(expected, mat.reshape(-1))
    expected = -expected if expected[0] < 0 else expected
    for flavour in FLAVOURS[:3]:
        got = _back(flavour, M.matrix_to_quat(_as(flavour, mat)))
        np.testing.assert_allclose(got, expected, atol=1e-12)
        assert got[0] >= 0
        np.testing.assert_allclose(_back(flavour, M.quat_to_matrix(_as(flavour, got))), mat, atol=1e-12)


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_euler_angles_are_extrinsic_xyz_in_degrees(rng: np.random.Generator, flavour: str) -> None:
    euler = rng.uniform(-180.0, 180.0, (N, 3))
    tol = 1e-12 if flavour != "torch-float32" else 1e-6  # float32 angles; the result is float64
    extrinsic = _mju(mujoco.mju_euler2Quat, 4, np.radians(euler), seq="XYZ")  # MuJoCo: capitals are fixed axes
    got = _back(flavour, M.euler_xyz_to_quat(_as(flavour, euler)), float64=True)
    np.testing.assert_allclose(got, extrinsic, atol=tol)
    intrinsic = _mju(mujoco.mju_euler2Quat, 4, np.radians(euler), seq="xyz")
    assert not np.allclose(got, intrinsic)
    rad = M.euler_xyz_to_quat(_as(flavour, np.radians(euler)), degrees=False)
    np.testing.assert_allclose(_back(flavour, rad, float64=True), extrinsic, atol=tol)
    # back to angles (y in [-90, 90] is unique away from gimbal lock)
    euler[:, 1] = rng.uniform(-89.0, 89.0, N)
    q = _mju(mujoco.mju_euler2Quat, 4, np.radians(euler), seq="XYZ")
    back = _back(flavour, M.quat_to_euler_xyz(_as(flavour, q)))
    np.testing.assert_allclose(back, euler, atol=1e-9 if flavour != "torch-float32" else 1e-3)
    back = _back(flavour, M.quat_to_euler_xyz(_as(flavour, q), degrees=False))
    np.testing.assert_allclose(back, np.radians(euler), atol=1e-9 if flavour != "torch-float32" else 1e-4)


def test_yaw_only_euler_angles_take_the_same_values(rng: np.random.Generator) -> None:
    euler = np.zeros((N, 3))
    euler[:, 2] = rng.uniform(-180.0, 180.0, N)
    expected = _mju(mujoco.mju_euler2Quat, 4, np.radians(euler), seq="XYZ")
    np.testing.assert_array_equal(M.euler_xyz_to_quat(euler), expected)
    np.testing.assert_allclose(M.euler_xyz_to_quat([0.0, 0.0, 90.0]), [np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_poses_match_mujoco(rng: np.random.Generator, flavour: str) -> None:
    a, b = _poses(rng), _poses(rng)
    tol = TOL[flavour]
    mats = _back(flavour, M.pose_to_matrix(_as(flavour, a)))
    np.testing.assert_allclose(mats[:, :3, :3], _mats(a[:, 3:]), atol=tol)
    np.testing.assert_allclose(mats[:, :3, 3], a[:, :3], atol=tol)
    np.testing.assert_array_equal(mats[:, 3], np.tile([0.0, 0.0, 0.0, 1.0], (N, 1)))
    canonical = a.copy()
    canonical[canonical[:, 3] < 0, 3:] *= -1  # matrix_to_pose returns w >= 0
    np.testing.assert_allclose(_back(flavour, M.matrix_to_pose(_as(flavour, mats))), canonical, atol=tol * 10)
    pos, quat = np.zeros((N, 3)), np.zeros((N, 4))
    for i in range(N):
        mujoco.mju_mulPose(pos[i], quat[i], a[i, :3], a[i, 3:], b[i, :3], b[i, 3:])
    got = _back(flavour, M.pose_mul(_as(flavour, a), _as(flavour, b)))
    np.testing.assert_allclose(got, np.concatenate([pos, quat], -1), atol=tol * 10)
    for i in range(N):
        mujoco.mju_negPose(pos[i], quat[i], a[i, :3], a[i, 3:])
    got = _back(flavour, M.pose_inverse(_as(flavour, a)))
    np.testing.assert_allclose(got, np.concatenate([pos, quat], -1), atol=tol * 10)


@pytest.mark.parametrize("flavour", FLAVOURS)
def test_compose_frames_matches_mujoco(rng: np.random.Generator, flavour: str) -> None:
    a, b = _poses(rng), _poses(rng)
    pos, quat = np.zeros((N, 3)), np.zeros((N, 4))
    for i in range(N):
        mujoco.mju_mulPose(pos[i], quat[i], a[i, :3], a[i, 3:], b[i, :3], b[i, 3:])
    args = (a[:, :3], _mats(a[:, 3:]), b[:, :3], _mats(b[:, 3:]))
    got_pos, got_rot = M.compose_frames(*(_as(flavour, x) for x in args))
    np.testing.assert_allclose(_back(flavour, got_pos), pos, atol=TOL[flavour] * 10)
    np.testing.assert_allclose(_back(flavour, got_rot), _mats(quat), atol=TOL[flavour] * 10)


def test_shapes_broadcast_and_single_values() -> None:
    q = M.euler_xyz_to_quat([0.0, 0.0, 90.0])
    assert q.shape == (4,)
    assert M.quat_to_matrix(q).shape == (3, 3)
    assert M.matrix_to_quat(np.eye(3)).tolist() == [1.0, 0.0, 0.0, 0.0]
    assert M.quat_mul(q, np.tile(q, (5, 2, 1))).shape == (5, 2, 4)
    np.testing.assert_allclose(M.quat_rotate(q, np.eye(3)), [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], atol=1e-15)
    assert M.pose_to_matrix(torch.zeros(2, 3, 7)).shape == (2, 3, 4, 4)
    assert M.matrix_to_quat(torch.eye(3).expand(4, 3, 3)).shape == (4, 4)  # broadcast views work
    assert M.quat_mul(torch.tensor([1.0, 0, 0, 0]), [0.0, 1.0, 0.0, 0.0]).tolist() == [0.0, 1.0, 0.0, 0.0]
    assert M.as_pose7(torch.eye(4)[None]).tolist() == [[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]
    pose = torch.zeros(3, 7)
    assert M.as_pose7(pose) is pose
    with pytest.raises(ValueError, match=r"\(N, 7\) or \(N, 4, 4\)"):
        M.as_pose7(torch.zeros(3, 6))


def test_gradients_flow_through_the_torch_path() -> None:
    euler = torch.tensor([[10.0, 20.0, 30.0]], dtype=torch.float64, requires_grad=True)
    pose = torch.cat((torch.zeros(1, 3, dtype=torch.float64), M.euler_xyz_to_quat(euler)), -1)
    M.matrix_to_quat(M.pose_to_matrix(pose)[:, :3, :3]).sum().backward()
    assert euler.grad is not None
    assert torch.isfinite(euler.grad).all()


def test_initial_pose_from_config() -> None:
    quat = np.zeros(4)
    mujoco.mju_euler2Quat(quat, np.radians([10.0, 20.0, 30.0]), "XYZ")
    np.testing.assert_array_equal(M.init_quat_from_cfg([10.0, 20.0, 30.0]), quat)
    local = np.eye(4)
    local[:3, :3], local[:3, 3] = _mats(quat[None])[0], (1.0, 2.0, 3.0)
    np.testing.assert_allclose(M.init_quat_from_cfg([0.0, 0.0, 0.0], local), quat, atol=1e-15)
    assert M.init_pos_from_cfg([0.0, 0.0, 0.0], local).tolist() == [1.0, 2.0, 3.0]
    assert M.init_pos_from_cfg((4, 5, 6)).tolist() == [4.0, 5.0, 6.0]


def test_docstring_examples_run() -> None:
    import doctest

    assert doctest.testmod(M, optionflags=doctest.NORMALIZE_WHITESPACE).failed == 0
