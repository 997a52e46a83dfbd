"""``DexforceW1Cfg``: the DexForce W1 wheeled dual-arm humanoid (EmbodiChain's config surface).

Example:
    >>> cfg = DexforceW1Cfg.from_dict({"uid": "dexforce_w1", "version": "v021",
    ...                                "arm_kind": "anthropomorphic", "init_pos": [0, 0, 0]})
    >>> scene.add_robot(cfg)        # 40 joints: torso 4, head 2, arms 7 + 7, BrainCo hands 10 + 10

``from_dict`` deep-merges ``drive_pros`` (your regexes take precedence) and
``solver_cfg`` (a part dict without ``class_type`` patches the default solver,
e.g. only its ``tcp``). Unknown keys are errors naming the key.
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional

from embodichain_core.sim.cfg import JointDrivePropertiesCfg, RigidBodyAttributesCfg
from embodichain_core.utils.configclass import configclass
from embodichain_robots.base_cfg import ProceduralRobotCfg
from embodichain_robots.dexforce_w1 import variants as V
from embodichain_robots.dexforce_w1.params import DRIVE_GROUPS


def default_drive_pros() -> JointDrivePropertiesCfg:
    """W1 drives: EmbodiChain's regex groups with MuJoCo-stable gains (see docs/robots.md)."""
    groups = DRIVE_GROUPS.values()
    return JointDrivePropertiesCfg(
        drive_type="force",
        stiffness={regex: kp for regex, kp, *_ in groups},
        damping={regex: kv for regex, _, kv, *_ in groups},
        max_effort={regex: effort for regex, _, _, effort, *_ in groups},
    )


@configclass
class DexforceW1Cfg(ProceduralRobotCfg):
    """The DexForce W1, generated procedurally (no vendor files).

    Attributes:
        version: ``v021`` (default), ``v022`` or ``v025`` (+12 mm flange).
        arm_kind: ``anthropomorphic`` (default; BrainCo hands) or ``industrial``
            (J6 +-90, J7 +-170 about the arm axis, DH_PGC_GRIPPER_M, TCP z 0.15).
        with_default_eef: mount the arm kind's default end effector on each
            side when ``hand_types`` does not say otherwise (False: 20 joints).
        hand_types: ``{side: brand}``; brands ``BRAINCO_HAND``, ``DH_PGC_GRIPPER``,
            ``DH_PGC_GRIPPER_M`` (case ignored).
        hand_versions: ``{side: "v021"}`` (the only hand version).
        hand_attach_xposes: ``{side: 4x4}`` hand mount in the ``{side}_ee`` frame.
    """

    version: str = "v021"
    arm_kind: str = "anthropomorphic"
    with_default_eef: bool = True
    hand_types: Optional[Dict[str, str]] = None
    hand_versions: Optional[Dict[str, str]] = None
    hand_attach_xposes: Optional[Dict[str, Any]] = None
    drive_pros: JointDrivePropertiesCfg = default_drive_pros()
    control_parts: Optional[Dict[str, List[str]]] = None
    solver_cfg: Optional[Dict[str, Any]] = None
    attrs: RigidBodyAttributesCfg = RigidBodyAttributesCfg(
        static_friction=0.95, dynamic_friction=0.9, contact_offset=0.001
    )
    min_position_iters: int = 32
    min_velocity_iters: int = 8

    def __post_init__(self) -> None:
        self.version = V.parse_version(self.version).value
        self.arm_kind = V.parse_arm_kind(self.arm_kind).value
        if self.hand_types is None and self.with_default_eef:
            self.hand_types = {side: V.default_brand(self.arm_kind).value for side in V.SIDES}
        self.hand_types = {side: b.value for side, b in V.parse_hands(self.hand_types or {}).items()}
        self.hand_versions = V.parse_hand_versions(self.hand_versions)
        self.hand_attach_xposes = V.parse_attach(self.hand_attach_xposes)
        if self.control_parts is None:
            self.control_parts = V.control_parts(self.hand_types)
        if self.solver_cfg is None:
            self.solver_cfg = V.default_solvers(self.version, self.arm_kind, self.hand_types)

    # -- the model -------------------------------------------------------------------------
    def build_spec(self) -> Any:
        """The W1 ``mujoco.MjSpec`` for this config (cameras, sites, mimic equalities)."""
        from embodichain_robots.dexforce_w1.model import build_w1_spec

        return build_w1_spec(V.options(self))
