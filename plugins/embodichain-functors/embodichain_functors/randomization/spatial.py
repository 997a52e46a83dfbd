"""Spatial randomization: object and articulation poses, robot joint positions and
end-effector poses (through the robot's IK), virtual targets; grid and anchor-height
layouts live in :mod:`embodichain_functors.randomization.layout`.

Rotations are extrinsic x-y-z Euler angles in degrees, poses ``(N, 7)`` xyz + wxyz
in the env frame. A relative rotation is applied in the initial pose's frame
(``R = R_init @ R_draw``), as EmbodiChain does.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
import torch

from embodichain_core.managers.cfg import SceneEntityCfg
from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.sim.entities.robot import Robot
from embodichain_core.utils.math import euler_xyz_to_quat as euler_to_quat
from embodichain_core.utils.math import pose_to_matrix, quat_mul
from embodichain_core.utils.math import pose_to_matrix as pose_matrix

from embodichain_functors._common import (
    ParamError,
    as_range,
    check_optional_range,
    entity_of,
    env_ids_of,
    uniform_np,
    validated,
)
from embodichain_functors._entities import joint_ids_of
from embodichain_functors._kinematics import check_ik, check_part, default_part, eef_pose, solve_ik
from embodichain_functors._sim import pose7_from_matrix, step_envs, write_model
from embodichain_functors.randomization.layout import planner_grid_cell_sampler, randomize_anchor_height

__all__ = [
    "get_random_pose",
    "randomize_rigid_object_pose",
    "randomize_robot_qpos",
    "randomize_robot_eef_pose",
    "randomize_articulation_root_pose",
    "randomize_target_pose",
    "planner_grid_cell_sampler",
    "randomize_anchor_height",
]


def get_random_pose(
    env: Any,
    init_pose: Any,
    position_range: Optional[Sequence] = None,
    rotation_range: Optional[Sequence] = None,
    relative_position: bool = True,
    relative_rotation: bool = False,
    env_ids: Any = None,
) -> torch.Tensor:
    """Draw one pose per row of ``init_pose`` ((n, 7) xyz + wxyz); returns (n, 7) float64.

    Without ``position_range`` the position stays ``init_pose``'s; a relative
    position adds the draw to it. Without ``rotation_range`` the orientation stays;
    a drawn rotation replaces it, or with ``relative_rotation`` composes with it.
    Row ``i`` draws from the episode stream of env ``env_ids[i]`` (default: env ``i``).
    """
    return torch.from_numpy(
        random_pose(env, init_pose, position_range, rotation_range, relative_position, relative_rotation, env_ids)
    )


def random_pose(
    env: Any,
    init_pose: Any,
    position_range: Optional[Sequence] = None,
    rotation_range: Optional[Sequence] = None,
    relative_position: bool = True,
    relative_rotation: bool = False,
    env_ids: Any = None,
) -> np.ndarray:
    """:func:`get_random_pose` as a new (n, 7) float64 numpy array (the hot-path form)."""
    if isinstance(init_pose, torch.Tensor):
        init_pose = init_pose.detach().cpu().numpy()
    pose = np.array(init_pose, dtype=np.float64)
    n = pose.shape[0]
    ids = np.arange(n) if env_ids is None else env_ids
    if position_range is not None:
        low, high = as_range(position_range, "get_random_pose", "position_range", 3)
        draw = uniform_np(env, ids, low, high)
        if relative_position:
            pose[:, :3] += draw
        else:
            pose[:, :3] = draw
    if rotation_range is not None:
        low, high = as_range(rotation_range, "get_random_pose", "rotation_range", 3)
        quat = euler_to_quat(uniform_np(env, ids, low, high))
        pose[:, 3:] = quat_mul(pose[:, 3:], quat) if relative_rotation else quat
    return pose


def _check_pose_ranges(functor: str, position_range: Any, rotation_range: Any) -> None:
    check_optional_range(position_range, functor, "position_range", 3)
    check_optional_range(rotation_range, functor, "rotation_range", 3)


def _check_rigid_pose(
    env: Any, entity_cfg: SceneEntityCfg, position_range: Any = None, rotation_range: Any = None, **_: Any
) -> None:
    entity_of(env, entity_cfg, "randomize_rigid_object_pose", (RigidObject,))
    _check_pose_ranges("randomize_rigid_object_pose", position_range, rotation_range)


@validated(_check_rigid_pose)
def randomize_rigid_object_pose(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    position_range: Any = None,
    rotation_range: Any = None,
    relative_position: bool = True,
    relative_rotation: bool = False,
    physics_update_step: int = -1,
) -> None:
    """Place a rigid object at a random pose per env around its configured initial pose.

    Velocities are cleared; with ``physics_update_step > 0`` only these envs are then
    simulated that many physics steps (to let the object settle).

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the rigid object (dynamic, kinematic or static).
        position_range: ``[[x, y, z] low, [x, y, z] high]`` in metres (``None``: keep).
        rotation_range: ``[[rx, ry, rz] low, [...] high]`` Euler degrees (``None``: keep).
        relative_position: add the drawn position to the initial position.
        relative_rotation: compose the drawn rotation with the initial orientation.
        physics_update_step: physics steps to simulate afterwards (``<= 0``: none).

    Example:
        ``{"func": "randomize_rigid_object_pose", "mode": "reset", "params": {"entity_cfg": {"uid": "cube"},
        "position_range": [[-0.1, -0.1, 0], [0.1, 0.1, 0]], "rotation_range": [[0, 0, -180], [0, 0, 180]]}}``
    """
    ids = env_ids_of(env, env_ids)
    obj = env.scene[entity_cfg.uid]
    init = np.broadcast_to(obj.init_pose.numpy(), (len(ids), 7))
    pose = random_pose(env, init, position_range, rotation_range, relative_position, relative_rotation, ids)
    obj.set_local_pose(pose, ids)
    obj.clear_dynamics(ids)
    step_envs(env, ids, physics_update_step)


def _qpos_joints(art: Articulation, entity_cfg: SceneEntityCfg, joint_ids: Optional[Sequence[int]]) -> list[int]:
    if joint_ids is not None:
        return [int(j) for j in joint_ids]
    return joint_ids_of(art, entity_cfg)


def _check_qpos(
    env: Any,
    entity_cfg: SceneEntityCfg,
    qpos_range: Any,
    relative_qpos: bool = True,
    joint_ids: Optional[Sequence[int]] = None,
) -> None:
    name = "randomize_robot_qpos"
    art = entity_of(env, entity_cfg, name, (Articulation,))
    joints = _qpos_joints(art, entity_cfg, joint_ids)
    if any(not 0 <= j < art.dof for j in joints):
        raise ParamError(name, "joint_ids", f"joint ids {joints} out of range for {art.dof} joints")
    as_range(qpos_range, name, "qpos_range", len(joints))


@validated(_check_qpos)
def randomize_robot_qpos(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    qpos_range: Any,
    relative_qpos: bool = True,
    joint_ids: Optional[Sequence[int]] = None,
) -> None:
    """Draw joint positions per env (teleported, drive targets set along, clamped to the limits).

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the robot or articulation; ``joint_names`` select joints.
        qpos_range: ``[low, high]``, numbers or one value per selected joint.
        relative_qpos: add the draw to the current joint positions.
        joint_ids: explicit joint ids (override ``entity_cfg.joint_names``; all joints by default).

    Example:
        ``{"func": "randomize_robot_qpos", "mode": "reset", "params": {"entity_cfg": {"uid": "robot",
        "joint_names": ["joint[1-7]"]}, "qpos_range": [-0.1, 0.1]}}``
    """
    ids = env_ids_of(env, env_ids)
    art = env.scene[entity_cfg.uid]
    joints = np.asarray(_qpos_joints(art, entity_cfg, joint_ids), dtype=np.int64)
    low, high = as_range(qpos_range, "randomize_robot_qpos", "qpos_range", len(joints))
    qpos = uniform_np(env, ids, low, high)
    if relative_qpos:
        qpos += art.qpos_array(ids, joints)
    limits = art.qpos_limits_array(ids, joints)
    qpos = np.minimum(np.maximum(qpos, limits[..., 0]), limits[..., 1])
    art.set_qpos(qpos, joint_ids=joints, env_ids=ids, target=False)
    art.clear_dynamics(ids)


def _eef_parts(env: Any, robot: Robot, entity_cfg: SceneEntityCfg) -> list[Optional[str]]:
    parts = entity_cfg.control_parts
    if parts is None:
        return [default_part(env, robot, None)]
    return [parts] if isinstance(parts, str) else list(parts)


def _check_eef(env: Any, entity_cfg: SceneEntityCfg, position_range: Any = None, rotation_range: Any = None) -> None:
    name = "randomize_robot_eef_pose"
    robot = entity_of(env, entity_cfg, name, (Robot,))
    for part in _eef_parts(env, robot, entity_cfg):
        check_part(robot, part, name, "entity_cfg")
        check_ik(robot, part, name, "entity_cfg")
    _check_pose_ranges(name, position_range, rotation_range)


@validated(_check_eef)
def randomize_robot_eef_pose(
    env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, position_range: Any = None, rotation_range: Any = None
) -> None:
    """Move a robot's end effector to a random pose around its current one, through IK.

    For each control part: forward kinematics of the current joints, a relative
    random offset (position added, rotation composed in the end-effector frame),
    inverse kinematics seeded with the current joints. Envs where IK fails keep
    their joints. The joints are teleported and their drive targets set.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the robot; ``control_parts`` names the parts (the env's first part by default).
        position_range: ``[[x, y, z] low, [...] high]`` offset in metres.
        rotation_range: ``[[rx, ry, rz] low, [...] high]`` offset in Euler degrees.

    Example:
        ``{"func": "randomize_robot_eef_pose", "mode": "reset", "params": {"entity_cfg": {"uid": "robot",
        "control_parts": ["arm"]}, "position_range": [[-0.03, -0.03, -0.03], [0.03, 0.03, 0.03]]}}``
    """
    ids = env_ids_of(env, env_ids)
    robot = env.scene[entity_cfg.uid]
    for part in _eef_parts(env, robot, entity_cfg):
        current = pose7_from_matrix(eef_pose(robot, part)[ids])
        target = get_random_pose(env, current, position_range, rotation_range, True, True, ids)
        _, qpos, joints = solve_ik(robot, pose_to_matrix(target).to(torch.float32), part, ids)
        robot.set_qpos(qpos, joint_ids=joints, env_ids=ids, target=False)
    robot.clear_dynamics(ids)


def _check_root(
    env: Any, entity_cfg: SceneEntityCfg, position_range: Any = None, rotation_range: Any = None, **_: Any
) -> None:
    entity_of(env, entity_cfg, "randomize_articulation_root_pose", (Articulation,))
    _check_pose_ranges("randomize_articulation_root_pose", position_range, rotation_range)


def _initial_root_pose(art: Articulation) -> torch.Tensor:
    """(7,) float64 CPU: a floating base's ``init_root_pose`` (edits to it are honoured), a
    fixed base's configured body pose."""
    if art.is_floating:
        return art.init_root_pose.to(device="cpu", dtype=torch.float64)
    model, body = art.scene.model, art.root_body_id
    return torch.as_tensor(list(model.body_pos[body]) + list(model.body_quat[body]), dtype=torch.float64)


@validated(_check_root)
def randomize_articulation_root_pose(
    env: Any,
    env_ids: Any,
    entity_cfg: SceneEntityCfg,
    position_range: Any = None,
    rotation_range: Any = None,
    relative_position: bool = True,
    relative_rotation: bool = False,
    physics_update_step: int = -1,
) -> None:
    """Place an articulation's root at a random pose per env around its configured pose.

    A floating base is teleported (velocities cleared); a fixed base is moved by
    its per-env body pose, so fixed-base robots and furniture can be placed too.
    Draws are relative to the configured initial pose, so repeated calls do not drift.

    Args:
        env: the env.
        env_ids: envs to randomize.
        entity_cfg: the articulation or robot.
        position_range: ``[[x, y, z] low, [...] high]`` in metres.
        rotation_range: ``[[rx, ry, rz] low, [...] high]`` Euler degrees.
        relative_position: add the draw to the initial position.
        relative_rotation: compose the drawn rotation with the initial orientation.
        physics_update_step: physics steps to simulate these envs afterwards.

    Example:
        ``{"func": "randomize_articulation_root_pose", "mode": "reset", "params": {"entity_cfg":
        {"uid": "drawer"}, "position_range": [[-0.05, -0.05, 0], [0.05, 0.05, 0]]}}``
    """
    ids = env_ids_of(env, env_ids)
    art = env.scene[entity_cfg.uid]
    init = _initial_root_pose(art).expand(len(ids), 7)
    pose = get_random_pose(env, init, position_range, rotation_range, relative_position, relative_rotation, ids)
    if art.is_floating:
        art.set_local_pose(pose, ids)
        art.clear_dynamics(ids)
    else:
        body = art.root_body_id
        write_model(env.sim, ids, [("body_pos", body, pose[:, :3]), ("body_quat", body, pose[:, 3:])])
    step_envs(env, ids, physics_update_step)


_IDENTITY_POSE = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def _check_target(
    env: Any,
    position_range: Any = None,
    rotation_range: Any = None,
    store_key: str = "goal_pose",
    reference_entity_cfg: Any = None,
    **_: Any,
) -> None:
    _check_pose_ranges("randomize_target_pose", position_range, rotation_range)
    if not isinstance(store_key, str) or not store_key.isidentifier():
        raise ParamError("randomize_target_pose", "store_key", f"must be an identifier, got {store_key!r}")
    current = getattr(env, store_key, None)
    if current is not None and not (isinstance(current, torch.Tensor) and current.shape == (env.num_envs, 4, 4)):
        raise ParamError("randomize_target_pose", "store_key", f"env.{store_key} exists and is not a (N, 4, 4) tensor")
    if reference_entity_cfg is not None:
        entity_of(
            env, reference_entity_cfg, "randomize_target_pose", (RigidObject, Articulation), "reference_entity_cfg"
        )


@validated(_check_target)
def randomize_target_pose(
    env: Any,
    env_ids: Any,
    position_range: Any = None,
    rotation_range: Any = None,
    relative_position: bool = False,
    relative_rotation: bool = False,
    reference_entity_cfg: Optional[SceneEntityCfg] = None,
    store_key: str = "goal_pose",
) -> None:
    """Draw a virtual goal pose per env into ``env.<store_key>`` ((N, 4, 4), created on first use).

    Args:
        env: the env.
        env_ids: envs to randomize.
        position_range: ``[[x, y, z] low, [...] high]`` in metres.
        rotation_range: ``[[rx, ry, rz] low, [...] high]`` Euler degrees.
        relative_position: add the draw to the reference entity's position (origin without one).
        relative_rotation: compose with the reference entity's orientation.
        reference_entity_cfg: entity whose current pose the relative draws start from.
        store_key: env attribute receiving the poses (read by ``target_position``, ``distance_to_target``,
            ``reaching_behind_object``: all default to ``goal_pose``).

    Example:
        ``{"func": "randomize_target_pose", "mode": "reset", "params": {"position_range":
        [[0.3, -0.2, 0.05], [0.6, 0.2, 0.05]], "store_key": "goal_pose"}}``
    """
    ids = env_ids_of(env, env_ids)
    if getattr(env, store_key, None) is None:
        setattr(env, store_key, torch.eye(4, device=getattr(env, "device", None)).repeat(env.num_envs, 1, 1))
    init = np.broadcast_to(_IDENTITY_POSE, (len(ids), 7))
    if reference_entity_cfg is not None:
        init = env.scene[reference_entity_cfg.uid].get_local_pose()[ids].to(torch.float64)
    pose = random_pose(env, init, position_range, rotation_range, relative_position, relative_rotation, ids)
    if rotation_range is None and reference_entity_cfg is None:  # identity rotations: only translations
        mats = np.repeat(np.eye(4)[None], len(ids), axis=0)
        mats[:, :3, 3] = pose[:, :3]
    else:
        mats = pose_matrix(pose)
    target = getattr(env, store_key)
    if target.device.type == "cpu" and not target.requires_grad:
        target.numpy()[ids.numpy()] = mats
    else:
        target[ids] = torch.from_numpy(mats).to(target)


#: The param naming the env attribute it writes (the readers are checked against it at build).
randomize_target_pose.writes_env_key = "store_key"  # type: ignore[attr-defined]
