"""``SevenDofArmCfg``: a Franka-like 7-DoF arm with a parallel gripper.

Control parts ``arm`` (``joint1..7``) and ``eef`` (``finger_joint1/2``; the
second finger is a mimic), an IK/FK solver for ``arm`` (``link0`` -> ``hand``,
TCP 0.1034 m out, between the finger pads), and the Panda "ready" home pose.

Example:
    >>> cfg = SevenDofArmCfg.from_dict({"uid": "arm", "init_pos": [0, 0, 0]})
    >>> # or from a gym config: {"robot": {"robot_type": "SevenDofArm", "uid": "arm"}}
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional

from embodichain_core.sim.cfg import JointDrivePropertiesCfg
from embodichain_core.utils.configclass import configclass
from embodichain_robots.base_cfg import ProceduralRobotCfg
from embodichain_robots.kinematics.solver import IKSolverCfg
from embodichain_robots.seven_dof_arm.model import HOME_QPOS, TCP_OFFSET

ARM_RE, FINGER_RE = "joint[1-7]", "finger_joint[12]"


def default_solvers() -> dict[str, IKSolverCfg]:
    """The ``arm`` solver: base ``link0`` to ``hand`` with the TCP between the pads."""
    tcp = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, TCP_OFFSET], [0, 0, 0, 1.0]]
    return {"arm": IKSolverCfg(root_link_name="link0", end_link_name="hand", tcp=tcp)}


@configclass
class SevenDofArmCfg(ProceduralRobotCfg):
    """The single arm for RL/IL tasks (see module docstring)."""

    drive_pros: JointDrivePropertiesCfg = JointDrivePropertiesCfg(
        drive_type="force",
        stiffness={ARM_RE: 1e4, FINGER_RE: 1e3},
        damping={ARM_RE: 1e3, FINGER_RE: 1e2},
        max_effort={"joint[1-4]": 87.0, "joint[5-7]": 12.0, FINGER_RE: 100.0},
    )
    control_parts: Optional[Dict[str, List[str]]] = {"arm": [ARM_RE], "eef": [FINGER_RE]}
    init_qpos: Optional[List[float]] = list(HOME_QPOS)
    solver_cfg: Optional[Dict[str, Any]] = None

    def __post_init__(self) -> None:
        if self.solver_cfg is None:
            self.solver_cfg = default_solvers()

    def build_spec(self) -> Any:
        """The arm's ``mujoco.MjSpec``."""
        from embodichain_robots.seven_dof_arm.model import build_arm_spec

        return build_arm_spec()
