"""{{ cookiecutter.task_id }}: {{ cookiecutter.description }}.

The robot is a 3-joint arm written inline in MJCF, so the task needs no other plugin.
The episode succeeds when the arm's ``ee`` link is within ``success_threshold`` of the
cube. This module is imported when the task is made, not when plugins load; the task is
registered by ``plugin.py`` (the tasks hook).
"""

from __future__ import annotations

from typing import Any, List

import torch

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers import EventCfg, ObservationCfg, RewardCfg, SceneEntityCfg
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.shapes import CubeCfg
from embodichain_core.utils.configclass import configclass

from {{ cookiecutter.package_name }}.functors import object_position, reach_distance, shift_object
from {{ cookiecutter.package_name }}.plugin import MAX_EPISODE_STEPS

ARM_MJCF = """
<mujoco model="{{ cookiecutter.package_name }}_arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <geom type="cylinder" size="0.05 0.02"/>
      <body name="link1" pos="0 0 0.04">
        <joint name="j1" axis="0 0 1" range="-3 3"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
        <body name="link2" pos="0 0 0.2">
          <joint name="j2" axis="0 1 0" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025"/>
          <body name="link3" pos="0.25 0 0">
            <joint name="j3" axis="0 1 0" range="-2 2"/>
            <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02"/>
            <body name="ee" pos="0.2 0 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@configclass
class {{ cookiecutter.class_name }}ArmCfg(RobotCfg):
    """The task's arm; registered as robot ``{{ cookiecutter.class_name }}Arm``."""

    uid: str = "arm"
    mjcf: str = ARM_MJCF
    control_parts: dict = {"arm": ["j[1-3]"]}


CUBE = SceneEntityCfg(uid="cube")


@configclass
class {{ cookiecutter.class_name }}Cfg(EmbodiedEnvCfg):
    """The scene and its functors; ``configs/gym_config.json`` describes the same env."""

    robot = {{ cookiecutter.class_name }}ArmCfg()
    control_parts = ["arm"]
    # annotated with the base class's type, so JSON configs loaded with this class as
    # cfg_cls convert their rigid_object entries
    rigid_object: List[RigidObjectCfg] = [
        RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.04, 0.04, 0.04]), init_pos=(0.4, 0.0, 0.02)),
    ]
    light = EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="lamp", light_type="point", init_pos=(0.0, 0.0, 2.0))])
    events = {
        "shift_cube": EventCfg(func=shift_object, mode="reset",
                               params={"entity_cfg": CUBE, "offset_range": (-0.05, 0.05)}),
    }
    observations = {
        "cube_pos": ObservationCfg(func=object_position, mode="add", name="object/cube_pos",
                                   params={"entity_cfg": CUBE}),
    }
    rewards = {"reach": RewardCfg(func=reach_distance, weight=1.0, params={"entity_cfg": CUBE})}
    extensions = {"success_threshold": 0.05}
    max_episode_steps = MAX_EPISODE_STEPS


class {{ cookiecutter.class_name }}Env(EmbodiedEnv):
    """{{ cookiecutter.description }}: success when ``ee`` is within ``success_threshold`` of the cube."""

    cfg_cls = {{ cookiecutter.class_name }}Cfg
    success_threshold: float

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        """``(success, fail, metrics)``, each with a leading ``num_envs`` dim."""
        ee = self.robot.get_link_pose("ee")[:, :3]
        cube = self.scene["cube"].get_local_pose()[:, :3]
        distance = torch.linalg.norm(ee - cube, dim=-1)
        success = distance < self.success_threshold
        return success, torch.zeros_like(success), {"distance": distance}
