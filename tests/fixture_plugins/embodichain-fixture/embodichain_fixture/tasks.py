"""FixtureReach-v0: reach a cube with a 3-joint arm (imported only when made)."""

import torch

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers import EventCfg, ObservationCfg, SceneEntityCfg
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.shapes import CubeCfg
from embodichain_core.utils.configclass import configclass

ARM = """
<mujoco model="fixture_arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base"><geom type="cylinder" size="0.05 0.02"/>
      <body name="l1" pos="0 0 0.04"><joint name="j1" axis="0 0 1" range="-3 3"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
        <body name="l2" pos="0 0 0.2"><joint name="j2" axis="0 1 0" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.025"/>
          <body name="l3" pos="0.25 0 0"><joint name="j3" axis="0 1 0" range="-2 2"/>
            <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02"/>
            <body name="ee" pos="0.2 0 0"/>
          </body></body></body></body>
  </worldbody>
</mujoco>
"""


@configclass
class FixtureArmCfg(RobotCfg):
    uid: str = "fixture_arm"
    mjcf: str = ARM
    control_parts: dict = {"arm": ["j[1-3]"]}


def cube_position(env, obs, entity_cfg):
    return env.scene[entity_cfg.uid].get_local_pose()[:, :3]


@configclass
class FixtureReachCfg(EmbodiedEnvCfg):
    robot = FixtureArmCfg()
    control_parts = ["arm"]
    rigid_object = [RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.04, 0.04, 0.04]), init_pos=(0.4, 0.0, 0.02))]
    light = EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="sun", light_type="point", init_pos=(0, 0, 2))])
    events = {
        "nudge": EventCfg(
            func="fixture_nudge_cube",
            mode="reset",
            params={"entity_cfg": SceneEntityCfg(uid="cube"), "offset_range": (-0.05, 0.05)},
        ),
    }
    observations = {
        "cube": ObservationCfg(
            func=cube_position, mode="add", name="object/cube_pos", params={"entity_cfg": SceneEntityCfg(uid="cube")}
        ),
    }
    extensions = {"success_threshold": 0.05}


class FixtureReachEnv(EmbodiedEnv):
    """Success when the end effector is within ``success_threshold`` of the cube."""

    cfg_cls = FixtureReachCfg

    def compute_task_state(self, **kwargs):
        ee = self.robot.get_link_pose("ee")[:, :3]
        cube = self.scene["cube"].get_local_pose()[:, :3]
        dist = torch.linalg.norm(ee - cube, dim=-1)
        return dist < self.success_threshold, torch.zeros_like(dist, dtype=torch.bool), {"distance": dist}
