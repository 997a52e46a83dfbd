"""``OpenDrawer-v1``: the W1 pulls the sliding drawer open by its handle with its right gripper.

Scene: the seed tutorial's round table with the ``SlidingBoxDrawer`` standing on it,
turned to face the robot (``init_rot`` (0, 0, 180), so its ``handle_xpos`` frame's +Z,
which points into the drawer, points away from the robot), in front of the right arm;
the point light and the ``eye_in_head`` stereo camera (320x180). Every reset draws the
drawer's position (+-3 cm x, +-5 cm y) and yaw (+-10 deg), the light and the table's
texture or colour. Actions are
joint position targets of ``right_arm`` (7) and ``right_eef`` (the two gripper fingers).

Success (measured on the simulated state): the drawer's ``slide_rails`` joint is open
more than ``open_threshold`` (0.15 m of its 0.2 m travel).

The scripted demo (:meth:`OpenDrawerEnv.create_demo_action_list`) reads the handle
frame, lowers the open gripper (pointing down, fingers closing along the opening
direction) so that its rear pad drops into the gap between the bar and the front panel,
closes it (the rear pad pushes the bar against the front pad: a clamp that the pull loads
through the pad's face, not through friction) and pulls along the handle's -Z by 0.17 m.

Example:
    >>> env = gym.make("OpenDrawer-v1", num_envs=4)         # doctest: +SKIP
    >>> env.reset(seed=0)                                   # doctest: +SKIP
    >>> for action in env.create_demo_action_list():        # doctest: +SKIP
    ...     obs, reward, terminated, truncated, info = env.step(action)
"""

from __future__ import annotations

from typing import Any, List

import torch

from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers.cfg import EventCfg, ObservationCfg
from embodichain_core.sim.cfg import ArticulationCfg, RigidObjectCfg, RobotCfg, SensorCfg, SimulationManagerCfg
from embodichain_core.utils.configclass import configclass
from embodichain_tasks.il import common

TASK_ID = "OpenDrawer-v1"
MAX_EPISODE_STEPS = 300
DRAWER_POS = (0.80, -0.18, 0.82)
DRAWER_ROT = (0.0, 0.0, 180.0)
#: Right arm ready pose: gripper pointing down 12 cm above and 8 cm in front of the
#: (unrandomized) handle, fingers closing along the drawer's opening direction.
RIGHT_READY = (-0.693, -1.2, 0.549, 1.446, 2.498, -1.259, -1.094)

#: Grasp offsets in the handle frame: the TCP (pad tips) goes this far in front of the bar
#: centre, so the open rear pad drops into the middle of the 2.5 cm gap behind the bar ...
GRASP_FRONT_OFFSET = 0.0125
#: ... and this far below it (the bar is 1 cm thick), so the pads cover the bar's height.
GRASP_DROP = 0.010
#: Pre-grasp height above the grasp and the pull length (travel limit 0.2 m; closing the
#: gripper already opens the drawer by about 1 cm: the rear pad pushes the bar against
#: the front pad).
APPROACH_HEIGHT = 0.10
PULL_DISTANCE = 0.17
#: Demo segment lengths in env steps (0.04 s each).
STEPS = {"reach": 25, "align": 5, "descend": 15, "settle": 5, "close": 12, "squeeze": 5, "pull": 80, "hold": 10}


def drawer_events() -> dict:
    """Startup contact settings; reset events: drawer pose, light, table material."""
    return {
        "grip_contacts": EventCfg(
            func="embodichain_tasks.il.common:tune_contacts", mode="startup", params={"impratio": 20.0}
        ),
        "drawer_pose": EventCfg(
            func="randomize_articulation_root_pose",
            mode="reset",
            params={
                "entity_cfg": {"uid": "drawer"},
                "position_range": [[-0.03, -0.05, 0.0], [0.03, 0.05, 0.0]],
                "rotation_range": [[0.0, 0.0, -10.0], [0.0, 0.0, 10.0]],
                "relative_rotation": True,
            },
        ),
        "light": common.light_event(),
        "table_material": common.table_material_event(),
    }


@configclass
class OpenDrawerCfg(EmbodiedEnvCfg):
    """The ``OpenDrawer-v1`` scene; ``configs/open_drawer.json`` is the same config as a file."""

    sim_cfg: SimulationManagerCfg = common.il_sim_cfg()
    robot: RobotCfg = common.w1_robot_cfg(RIGHT_READY)
    control_parts: List[str] = ["right_arm", "right_eef"]
    sensor: List[SensorCfg] = [common.eye_in_head_cfg()]
    light: EmbodiedEnvCfg.EnvLightCfg = EmbodiedEnvCfg.EnvLightCfg(direct=[common.point_light_cfg()])
    background: List[RigidObjectCfg] = [common.round_table_cfg()]
    articulation: List[ArticulationCfg] = [
        ArticulationCfg(
            uid="drawer", fpath="SlidingBoxDrawer/SlidingBoxDrawer.urdf", init_pos=DRAWER_POS, init_rot=DRAWER_ROT
        ),
    ]
    events: Any = drawer_events()
    observations: Any = {
        "handle_pose": ObservationCfg(
            func="embodichain_tasks.il.open_drawer:handle_pose", mode="add", name="handle_pose"
        ),
        "drawer_opening": ObservationCfg(
            func="embodichain_tasks.il.open_drawer:drawer_opening", mode="add", name="drawer_opening"
        ),
    }
    extensions: Any = {"open_threshold": 0.15}
    max_episode_steps: int = MAX_EPISODE_STEPS


def handle_pose(env: Any, obs: Any = None) -> torch.Tensor:
    """Observation functor: (N, 4, 4) pose of the drawer's ``handle_xpos`` frame."""
    return env.scene["drawer"].get_link_pose("handle_xpos", to_matrix=True).float()


def drawer_opening(env: Any, obs: Any = None) -> torch.Tensor:
    """Observation functor: (N, 1) opening of the drawer's ``slide_rails`` joint (m)."""
    return env.scene["drawer"].get_qpos()[:, :1].float()


class OpenDrawerEnv(EmbodiedEnv):
    """Pull the drawer open by its handle (see the module docstring)."""

    cfg_cls = OpenDrawerCfg

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        opening = self.scene["drawer"].get_qpos()[:, 0].float()
        success = opening > getattr(self, "open_threshold", 0.15)
        return success, torch.zeros_like(success), {"drawer_opening": opening}

    def is_task_success(self, **kwargs: Any) -> torch.Tensor:
        """The drawer is open more than ``open_threshold``."""
        return self.compute_task_state()[0]

    # -- scripted demo -------------------------------------------------------------------
    def grasp_pose(self) -> torch.Tensor:
        """(N, 4, 4) TCP pose at the grasp: pointing down, fingers closing along the opening
        direction, the open rear pad in the gap between the handle bar and the front panel."""
        handle = self.scene["drawer"].get_link_pose("handle_xpos", to_matrix=True).to(torch.float64)
        up, into = handle[:, :3, 0], handle[:, :3, 2]
        rotation = common.frame_from_axes(-up, -into)
        position = handle[:, :3, 3] - GRASP_FRONT_OFFSET * into - GRASP_DROP * up
        return common.make_pose(rotation, position)

    def create_demo_action_list(self, **kwargs: Any) -> list[torch.Tensor]:
        """Reach above the handle, descend, clamp the bar, pull: (num_envs, 9) targets per step.

        The pull is slow (80 steps for 17 cm): at twice the speed the arm's tracking lag
        makes the rear pad strike the bar and the clamp loses it in about 1 of 5 episodes.
        """
        grasp = self.grasp_pose()
        above, pulled = grasp.clone(), grasp.clone()
        above[:, 2, 3] += APPROACH_HEIGHT
        pulled[:, :3, 3] += PULL_DISTANCE * grasp[:, :3, 1]  # closing axis = -into: the opening direction
        demo = common.DemoBuilder(self, arm="right_arm", eef="right_eef")
        demo.set_gripper(0.0, 1)
        demo.move_to_pose(above, STEPS["reach"])
        demo.hold(STEPS["align"])
        demo.linear_to_pose(grasp, STEPS["descend"])
        demo.hold(STEPS["settle"])
        demo.set_gripper(1.0, STEPS["close"])
        demo.hold(STEPS["squeeze"])
        demo.linear_to_pose(pulled, STEPS["pull"])
        demo.hold(STEPS["hold"])
        self.demo_ik_ok = demo.ik_ok
        return demo.actions()
