"""``PushCube-v1``: a 7-DoF arm pushes a cube to a random goal on a table (RL).

The scene: :class:`~embodichain_robots.SevenDofArmCfg` (gripper closed, only the seven
arm joints active) standing on a table, a 6 cm cube placed at random in front of it
and a virtual goal (``env.goal_pose``, drawn by ``randomize_target_pose`` relative to
the cube). Actions are delta joint positions (``DeltaQposTerm``, scale 0.1 rad per
unit action, actions in [-1, 1]). Observations: joint positions and velocities, the
cube pose, the goal position and the end-effector position.

Reward (functors, EmbodiChain's PushCubeRL weights): ``reaching_behind_object`` (0.03),
``distance_to_target`` (exponential, sigma 0.12, xy only; 0.8),
``action_smoothness_penalty`` (0.01) and ``success_reward`` (10). Success: the cube's
xy within ``success_threshold`` (an ``extensions`` value, 0.1 m) of the goal, reported
every step. Episodes do not end on success (``ignore_terminations``): the task is to push
the cube there and keep it there, and ``success_reward`` pays for every step at the goal
(ending at the first success would make a solved episode worth no more than an idle
one). Truncated when the cube falls off the table (``fall_depth`` below its starting
height), and at the episode limit (100 steps).

The JSON twin of :class:`PushCubeCfg` is ``embodichain_tasks/configs/push_cube.json``.

Example:
    >>> import gymnasium as gym, torch
    >>> env = gym.make("PushCube-v1", num_envs=8)  # doctest: +SKIP
    >>> obs, info = env.reset(seed=0)  # doctest: +SKIP
    >>> obs, reward, terminated, truncated, info = env.step(torch.zeros(8, 7))  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

import torch

import embodichain_functors.actions as actions
import embodichain_functors.observations as observations
import embodichain_functors.randomization as rand
import embodichain_functors.rewards as rewards
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers import ActionTermCfg, EventCfg, ObservationCfg, RewardCfg, SceneEntityCfg
from embodichain_core.sim.cfg import LightCfg, RigidBodyAttributesCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.shapes import CubeCfg, VisualMaterialCfg
from embodichain_core.utils.configclass import configclass
from embodichain_robots import SevenDofArmCfg

__all__ = ["PushCubeCfg", "PushCubeEnv", "TABLE_TOP", "CUBE_SIZE"]

#: Height of the table top (metres); the arm stands on it.
TABLE_TOP = 0.4
#: Edge length of the cube (metres).
CUBE_SIZE = 0.06
#: Arm pose at reset: gripper closed and pointing down, its TCP at (0.33, 0, 0.44) (behind the cube, at its height).
ARM_INIT_QPOS = [0.0, 0.18, 0.0, -2.9, 0.0, 3.08, 0.785, 0.0, 0.0]


def _entity(uid: str) -> SceneEntityCfg:
    return SceneEntityCfg(uid=uid)


@configclass
class PushCubeEventCfg:
    """Reset events: the cube's position, then the goal relative to it."""

    randomize_cube: EventCfg = EventCfg(
        func=rand.randomize_rigid_object_pose,
        mode="reset",
        params={
            "entity_cfg": _entity("cube"),
            "position_range": [[-0.05, -0.1, 0.0], [0.05, 0.1, 0.0]],
            "relative_position": True,
        },
    )
    randomize_goal: EventCfg = EventCfg(
        func=rand.randomize_target_pose,
        mode="reset",
        params={
            "position_range": [[0.15, -0.1, 0.0], [0.25, 0.1, 0.0]],
            "relative_position": True,
            "reference_entity_cfg": _entity("cube"),
            "store_key": "goal_pose",
        },
    )


@configclass
class PushCubeObsCfg:
    """Task observations added to ``robot/{qpos,qvel,qf}``."""

    cube_pose: ObservationCfg = ObservationCfg(
        func=observations.get_rigid_object_pose,
        mode="add",
        name="cube_pose",
        params={"entity_cfg": _entity("cube"), "to_matrix": False},
    )
    goal_position: ObservationCfg = ObservationCfg(
        func=observations.target_position, mode="add", name="goal_position", params={"target_pose_key": "goal_pose"}
    )
    eef_position: ObservationCfg = ObservationCfg(
        func=observations.get_robot_eef_pose,
        mode="add",
        name="eef_position",
        params={"part_name": "arm", "position_only": True},
    )


@configclass
class PushCubeRewardCfg:
    """EmbodiChain's PushCubeRL reward functors and weights."""

    reaching_reward: RewardCfg = RewardCfg(
        func=rewards.reaching_behind_object,
        mode="add",
        weight=0.03,
        params={
            "object_cfg": _entity("cube"),
            "target_pose_key": "goal_pose",
            "behind_offset": 0.05,
            "height_offset": 0.0,
            "part_name": "arm",
        },
    )
    place_reward: RewardCfg = RewardCfg(
        func=rewards.distance_to_target,
        mode="add",
        weight=0.8,
        params={
            "source_entity_cfg": _entity("cube"),
            "target_pose_key": "goal_pose",
            "exponential": True,
            "sigma": 0.12,
            "use_xy_only": True,
        },
    )
    action_penalty: RewardCfg = RewardCfg(func=rewards.action_smoothness_penalty, mode="add", weight=0.01)
    success_bonus: RewardCfg = RewardCfg(func=rewards.success_reward, mode="add", weight=10.0)


@configclass
class PushCubeActionCfg:
    """Delta joint positions of the seven arm joints."""

    delta_qpos: ActionTermCfg = ActionTermCfg(func=actions.DeltaQposTerm, params={"scale": 0.1})


@configclass
class PushCubeCfg(EmbodiedEnvCfg):
    """The PushCube-v1 scene and managers (see the module docstring)."""

    robot: RobotCfg = SevenDofArmCfg(uid="arm", init_pos=(0.0, 0.0, TABLE_TOP), init_qpos=list(ARM_INIT_QPOS))
    control_parts = ["arm"]
    max_episode_steps: int = 100
    ignore_terminations: bool = True
    light: EmbodiedEnvCfg.EnvLightCfg = EmbodiedEnvCfg.EnvLightCfg(
        direct=[LightCfg(uid="lamp", light_type="point", intensity=30.0, init_pos=(0.5, 0.0, 2.0))]
    )
    background = [
        RigidObjectCfg(
            uid="table",
            shape=CubeCfg(
                size=[1.2, 1.0, TABLE_TOP], visual_material=VisualMaterialCfg(base_color=(0.55, 0.4, 0.28, 1))
            ),
            body_type="static",
            init_pos=(0.35, 0.0, TABLE_TOP / 2),
        ),
    ]
    rigid_object = [
        RigidObjectCfg(
            uid="cube",
            shape=CubeCfg(size=[CUBE_SIZE] * 3, visual_material=VisualMaterialCfg(base_color=(0.9, 0.2, 0.2, 1))),
            attrs=RigidBodyAttributesCfg(mass=0.2, static_friction=0.6, dynamic_friction=0.5),
            init_pos=(0.45, 0.0, round(TABLE_TOP + CUBE_SIZE / 2, 6)),
        ),
    ]
    events = PushCubeEventCfg()
    observations = PushCubeObsCfg()
    rewards = PushCubeRewardCfg()
    actions = PushCubeActionCfg()
    extensions = {"success_threshold": 0.1, "fall_depth": 0.1}


class PushCubeEnv(EmbodiedEnv):
    """Push the cube to ``env.goal_pose`` (see the module docstring).

    Attributes (from ``extensions``): ``success_threshold`` (xy metres) and
    ``fall_depth`` (metres below its starting height that count as fallen off the table).
    """

    cfg_cls = PushCubeCfg
    success_threshold: float
    fall_depth: float
    goal_pose: torch.Tensor

    def _cube_position(self) -> torch.Tensor:
        return self.scene["cube"].get_local_pose(to_matrix=True)[:, :3, 3].float()

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        """Success: cube xy within ``success_threshold`` of the goal; never a failure."""
        distance = (self._cube_position()[:, :2] - self.goal_pose[:, :2, 3]).norm(dim=-1)
        success = distance < self.success_threshold
        return success, torch.zeros_like(success), {"distance_to_goal": distance}

    def check_truncated(self, obs: Any, info: dict) -> torch.Tensor:
        """The cube fell off the table: ``fall_depth`` below its initial height."""
        start_z = float(self.scene["cube"].init_pose[2])
        return self._cube_position()[:, 2] < start_z - self.fall_depth
