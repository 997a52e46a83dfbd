"""``PickFork-v1``: the W1 picks the fork from the round table with its right gripper and lifts it.

Scene: the seed tutorial's round table, a fork (one of the six variants of
``TableWare/tableware/fork/``, scaled 0.75 x 0.75 x 1 as in the tutorial) lying on it in
front of the right arm, the point light and the ``eye_in_head`` stereo camera (320x180).
Every reset draws the fork's mesh, mass (30-100 g), position (+-4 cm x, +-5 cm y) and
yaw (+-30 deg), the light and the table's texture or colour. Actions are joint position
targets of ``right_arm`` (7) and ``right_eef`` (the two gripper fingers).

Success (measured on the simulated state): the fork's centre of mass is more than
``lift_height`` (0.1 m) above the table top and within ``hold_distance`` (4 cm) of the
gripper's TCP, i.e. lifted and held. The fork falling off the table is a failure.

The scripted demo (:meth:`PickForkEnv.create_demo_action_list`) reads the fork pose,
grasps its centre of mass from above, fingers closing across the fork, and lifts it.

Example:
    >>> env = gym.make("PickFork-v1", num_envs=4)          # doctest: +SKIP
    >>> env.reset(seed=0)                                   # doctest: +SKIP
    >>> for action in env.create_demo_action_list():        # doctest: +SKIP
    ...     obs, reward, terminated, truncated, info = env.step(action)
"""

from __future__ import annotations

from typing import Any, List

import torch

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers.cfg import EventCfg, ObservationCfg
from embodichain_core.sim.cfg import RigidBodyAttributesCfg, RigidObjectCfg, RobotCfg, SensorCfg, SimulationManagerCfg
from embodichain_core.sim.shapes import MeshCfg
from embodichain_core.utils.configclass import configclass
from embodichain_core.utils.math import quat_to_matrix
from embodichain_tasks.il import common

TASK_ID = "PickFork-v1"
MAX_EPISODE_STEPS = 300
FORK_FOLDER = "TableWare/tableware/fork/"
#: Fork origin resting on the table (top at 0.82; the fork is 5 mm thick).
FORK_POS = (0.50, -0.20, 0.8225)

#: Pad tips this far above the table top at the grasp (the fork is 4-5 mm thick).
GRASP_CLEARANCE = 0.002
#: Pre-grasp and lift heights of the TCP over the grasp point.
APPROACH_HEIGHT = 0.10
LIFT_HEIGHT = 0.18
#: Demo segment lengths in env steps (0.04 s each).
STEPS = {"reach": 30, "align": 5, "descend": 15, "settle": 5, "close": 12, "squeeze": 5, "lift": 50, "hold": 10}


def fork_events() -> dict:
    """Startup contact settings; reset events: fork mesh, mass and pose, light, table material."""
    fork = {"uid": "fork"}
    return {
        "replace_fork": EventCfg(
            func="replace_assets_from_group", mode="reset", params={"entity_cfg": fork, "folder_path": FORK_FOLDER}
        ),
        "grip_contacts": EventCfg(
            func="embodichain_tasks.il.common:tune_contacts", mode="startup", params={"impratio": 20.0}
        ),
        "fork_mass": EventCfg(
            func="randomize_rigid_object_mass", mode="reset", params={"entity_cfg": fork, "mass_range": [0.03, 0.1]}
        ),
        "fork_pose": EventCfg(
            func="randomize_rigid_object_pose",
            mode="reset",
            params={
                "entity_cfg": fork,
                "position_range": [[-0.04, -0.05, 0.0], [0.04, 0.05, 0.0]],
                "rotation_range": [[0.0, 0.0, -30.0], [0.0, 0.0, 30.0]],
                "relative_rotation": True,
            },
        ),
        "light": common.light_event(),
        "table_material": common.table_material_event(),
    }


def fork_com(env: Any, obs: Any = None) -> torch.Tensor:
    """Observation functor: (N, 3) the fork's centre of mass in the env frame.

    The fork's origin pose (``get_rigid_object_pose``) does not say which of the six meshes
    the reset drew; their centres of mass lie up to 1 cm apart along the fork, and the
    scripted demonstration grasps above the centre of mass.
    """
    return env.fork_com().float()


@configclass
class PickForkCfg(EmbodiedEnvCfg):
    """The ``PickFork-v1`` scene; ``configs/pick_fork.json`` is the same config as a file."""

    sim_cfg: SimulationManagerCfg = common.il_sim_cfg()
    robot: RobotCfg = common.w1_robot_cfg()
    control_parts: List[str] = ["right_arm", "right_eef"]
    sensor: List[SensorCfg] = [common.eye_in_head_cfg()]
    light: EmbodiedEnvCfg.EnvLightCfg = EmbodiedEnvCfg.EnvLightCfg(direct=[common.point_light_cfg()])
    background: List[RigidObjectCfg] = [common.round_table_cfg()]
    rigid_object: List[RigidObjectCfg] = [
        RigidObjectCfg(
            uid="fork",
            shape=MeshCfg(fpath=FORK_FOLDER + "standard_fork_scale.ply"),
            attrs=RigidBodyAttributesCfg(mass=0.05, static_friction=1.0),
            body_scale=(0.75, 0.75, 1.0),
            init_pos=FORK_POS,
        ),
    ]
    events: Any = fork_events()
    observations: Any = {
        "fork_pose": ObservationCfg(
            func="get_rigid_object_pose", mode="add", name="fork_pose", params={"entity_cfg": {"uid": "fork"}}
        )
    }
    extensions: Any = {"lift_height": 0.1, "hold_distance": 0.04}
    max_episode_steps: int = MAX_EPISODE_STEPS


class PickForkEnv(EmbodiedEnv):
    """Pick the fork up from the table (see the module docstring)."""

    cfg_cls = PickForkCfg

    # -- task state ------------------------------------------------------------------------
    def fork_com(self) -> torch.Tensor:
        """(N, 3) fork centre of mass in the env frame."""
        fork = self.scene["fork"]
        pose = fork.get_local_pose().to(torch.float64)
        rot = quat_to_matrix(pose[:, 3:])
        return pose[:, :3] + (rot @ fork.get_com().to(torch.float64).unsqueeze(-1)).squeeze(-1)

    def table_top(self) -> torch.Tensor:
        """(N,) height of the table top."""
        return self.scene["table"].get_local_pose()[:, 2].to(torch.float64) + common.TABLE_TOP_OFFSET

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        com = self.fork_com()
        height = com[:, 2] - self.table_top()
        tcp = self.robot.compute_fk(name="right_arm").to(torch.float64)[:, :3, 3]
        distance = torch.linalg.norm(com - tcp, dim=-1)
        lift, hold = getattr(self, "lift_height", 0.1), getattr(self, "hold_distance", 0.04)
        success = (height > lift) & (distance < hold)
        fail = height < -0.1
        return success, fail, {"fork_height": height.float(), "fork_tcp_distance": distance.float()}

    def is_task_success(self, **kwargs: Any) -> torch.Tensor:
        """Lifted above ``lift_height`` and held within ``hold_distance`` of the TCP."""
        return self.compute_task_state()[0]

    # -- scripted demo -------------------------------------------------------------------
    def grasp_pose(self) -> torch.Tensor:
        """(N, 4, 4) TCP pose at the grasp: above the fork's centre of mass, pointing down,
        fingers closing across the fork, pad tips :data:`GRASP_CLEARANCE` over the table."""
        fork_rot = quat_to_matrix(self.scene["fork"].get_local_pose()[:, 3:].to(torch.float64))
        rotation = common.top_down_grasp_frame(common.yaw_of(fork_rot))
        position = self.fork_com()
        position[:, 2] = self.table_top() + GRASP_CLEARANCE
        return common.make_pose(rotation, position)

    def create_demo_action_list(self, **kwargs: Any) -> list[torch.Tensor]:
        """Reach above the fork, descend, close the gripper, lift: (num_envs, 9) targets per step."""
        grasp = self.grasp_pose()
        above, lifted = grasp.clone(), grasp.clone()
        above[:, 2, 3] += APPROACH_HEIGHT
        lifted[:, 2, 3] += LIFT_HEIGHT
        demo = common.DemoBuilder(self, arm="right_arm", eef="right_eef")
        demo.set_gripper(0.0, 1)
        demo.move_to_pose(above, STEPS["reach"])
        demo.hold(STEPS["align"])
        demo.linear_to_pose(grasp, STEPS["descend"])
        demo.hold(STEPS["settle"])
        demo.set_gripper(1.0, STEPS["close"])
        demo.hold(STEPS["squeeze"])
        demo.linear_to_pose(lifted, STEPS["lift"])
        demo.hold(STEPS["hold"])
        self.demo_ik_ok = demo.ik_ok
        return demo.actions()
