"""Shared helpers of the scripted IL demos: grasp frames, IK paths, joint interpolation.

A demo is a list of per-step joint position targets for the env's active joints,
shape ``(num_envs, len(env.active_joint_ids))`` each. :class:`DemoBuilder` keeps
one arm part and one end-effector part of the robot and appends segments:

* :meth:`DemoBuilder.move_to_pose`: joint-space move (smooth-step profile) to the
  IK solution of a TCP pose, for large moves between free-space waypoints;
* :meth:`DemoBuilder.linear_to_pose`: a straight TCP line, solved by IK at every
  step (each solve seeded with the previous one), for approach, lift and pull;
* :meth:`DemoBuilder.set_gripper` / :meth:`DemoBuilder.hold`: open or close the
  hand or gripper (a fraction of its joint range) while the arm holds still.

Every IK call is batched over the envs, so one demo serves every env of a batch
(each from its own randomized state). The targets stay on the env's device (a GPU's).

Example:
    >>> demo = DemoBuilder(env, arm="right_arm", eef="right_eef")  # doctest: +SKIP
    >>> demo.move_to_pose(pre_grasp, steps=25)                      # doctest: +SKIP
    >>> demo.linear_to_pose(grasp, steps=12)                        # doctest: +SKIP
    >>> demo.set_gripper(1.0, steps=10)                             # doctest: +SKIP
    >>> actions = demo.actions()  # list of (num_envs, action_dim) tensors  # doctest: +SKIP
"""

from __future__ import annotations

import math
from typing import Any, Optional, Sequence

import torch

from embodichain_core.managers.functor import Functor

__all__ = [
    "DemoBuilder",
    "frame_from_axes",
    "top_down_grasp_frame",
    "make_pose",
    "smooth_step",
    "interpolate_joints",
    "yaw_of",
    "w1_init_qpos",
    "w1_robot_cfg",
    "il_sim_cfg",
    "eye_in_head_cfg",
    "round_table_cfg",
    "point_light_cfg",
    "light_event",
    "table_material_event",
    "tune_contacts",
]


def frame_from_axes(approach: torch.Tensor, closing: torch.Tensor) -> torch.Tensor:
    """(N, 3, 3) gripper rotation whose z axis is ``approach`` and y axis ``closing``.

    Args:
        approach: (N, 3) or (3,) direction the fingers point (TCP z axis).
        closing: (N, 3) or (3,) direction the fingers close along (TCP y axis); it is
            made orthogonal to ``approach``.
    """
    z = torch.nn.functional.normalize(torch.as_tensor(approach, dtype=torch.float64), dim=-1)
    y = torch.as_tensor(closing, dtype=torch.float64)
    y, z = torch.broadcast_tensors(y, z)
    y = torch.nn.functional.normalize(y - (y * z).sum(-1, keepdim=True) * z, dim=-1)
    x = torch.linalg.cross(y, z, dim=-1)
    return torch.stack([x, y, z], dim=-1).reshape(-1, 3, 3)


def top_down_grasp_frame(yaw: torch.Tensor) -> torch.Tensor:
    """(N, 3, 3) rotation of a gripper pointing down that closes across a long object.

    Args:
        yaw: (N,) yaw (rad) of the object's long axis in the env frame; the fingers
            close perpendicular to it.
    """
    yaw = torch.as_tensor(yaw, dtype=torch.float64).reshape(-1)
    closing = torch.stack([-torch.sin(yaw), torch.cos(yaw), torch.zeros_like(yaw)], dim=-1)
    down = torch.tensor([0.0, 0.0, -1.0], dtype=torch.float64, device=yaw.device).expand(len(yaw), 3)
    return frame_from_axes(down, closing)


def yaw_of(rotation: torch.Tensor, fold: bool = True) -> torch.Tensor:
    """(N,) yaw of the x axis of (N, 3, 3) rotations, folded into [-pi/2, pi/2) when
    ``fold`` (a parallel gripper is symmetric under a half turn)."""
    x_axis = rotation[..., :, 0]
    yaw = torch.atan2(x_axis[..., 1], x_axis[..., 0])
    if fold:
        yaw = torch.remainder(yaw + math.pi / 2, math.pi) - math.pi / 2
    return yaw


def make_pose(rotation: torch.Tensor, position: torch.Tensor) -> torch.Tensor:
    """(N, 4, 4) homogeneous poses from (N, 3, 3) rotations and (N, 3) positions (on the
    positions' device)."""
    position = torch.as_tensor(position, dtype=torch.float64)
    rotation = torch.as_tensor(rotation, dtype=torch.float64).expand(position.shape[0], 3, 3)
    pose = torch.eye(4, dtype=torch.float64, device=position.device).repeat(position.shape[0], 1, 1)
    pose[:, :3, :3] = rotation
    pose[:, :3, 3] = position
    return pose


def smooth_step(steps: int) -> torch.Tensor:
    """(steps,) progress values in (0, 1] with zero start and end velocity (cosine)."""
    t = torch.arange(1, steps + 1, dtype=torch.float64) / steps
    return 0.5 - 0.5 * torch.cos(math.pi * t)


def interpolate_joints(start: torch.Tensor, goal: torch.Tensor, steps: int) -> torch.Tensor:
    """(steps, N, k) joint targets from ``start`` to ``goal`` (both (N, k), on one device), smooth-step."""
    s = smooth_step(steps).to(start.device, start.dtype).view(-1, 1, 1)
    return start.unsqueeze(0) + s * (goal - start).unsqueeze(0)


class DemoBuilder:
    """Builds a scripted demo for one arm part and one end-effector part.

    Args:
        env: the env (its robot, ``active_joint_ids`` and current state are read).
        arm: the arm control part solved by IK (``robot.compute_ik(name=arm)``).
        eef: the hand or gripper control part, or None.
        eef_closed_high: whether a closed hand is the upper end of the eef joint
            ranges (True for the W1 grippers and BrainCo fingers).
    """

    def __init__(self, env: Any, arm: str, eef: Optional[str] = None, eef_closed_high: bool = True):
        self.env, self.robot, self.arm = env, env.robot, arm
        self.full = self.robot.get_qpos(target=True).to(torch.float64)

        def index(ids: Any) -> torch.Tensor:  # copied to the device once, not at every row
            return torch.as_tensor(list(ids), dtype=torch.long, device=self.full.device)

        self.arm_ids = index(self.robot.get_solver(arm).joint_ids)
        self.eef_ids = index(self.robot.get_joint_ids(eef, remove_mimic=True) if eef else [])
        self._active = index(env.active_joint_ids)
        limits = self.robot.get_qpos_limits().to(self.full.device)[:, self.eef_ids].to(torch.float64)
        self._eef_open = limits[..., 0] if eef_closed_high else limits[..., 1]
        self._eef_closed = limits[..., 1] if eef_closed_high else limits[..., 0]
        self.arm_q = self.full[:, self.arm_ids].clone()
        self.ik_ok = torch.ones(env.num_envs, dtype=torch.bool, device=self.full.device)
        self._rows: list[torch.Tensor] = []

    # -- segments -------------------------------------------------------------------------
    def solve(self, pose: torch.Tensor, seed: Optional[torch.Tensor] = None) -> torch.Tensor:
        """IK of (N, 4, 4) TCP ``pose`` seeded with ``seed`` (default: the last target);
        failures are recorded in :attr:`ik_ok` (the best attempt is still returned)."""
        seed = self.arm_q if seed is None else seed
        ok, q = self.robot.compute_ik(pose, joint_seed=seed, name=self.arm)
        self.ik_ok &= ok.to(self.ik_ok.device)
        return q.to(self.full.device, torch.float64)

    def move_to_pose(self, pose: torch.Tensor, steps: int) -> torch.Tensor:
        """Joint-space move to the IK solution of ``pose``; returns that solution."""
        goal = self.solve(pose)
        self._append_arm(interpolate_joints(self.arm_q, goal, steps))
        return goal

    def linear_to_pose(self, pose: torch.Tensor, steps: int) -> None:
        """Straight TCP line from the current arm target to ``pose`` (its rotation kept),
        smooth-step timed, with one IK solve per step."""
        start = self.robot.compute_fk(self.arm_q.to(torch.float32), name=self.arm).to(torch.float64)
        path: list[torch.Tensor] = []
        for s in smooth_step(steps):
            waypoint = pose.clone()
            waypoint[:, :3, 3] = start[:, :3, 3] + s * (pose[:, :3, 3] - start[:, :3, 3])
            path.append(self.solve(waypoint, seed=path[-1] if path else self.arm_q))
        self._append_arm(torch.stack(path))

    def set_gripper(self, closed: float, steps: int) -> None:
        """Drive the eef to ``closed`` (0 open .. 1 closed) over ``steps``, arm still."""
        goal = self._eef_open + float(closed) * (self._eef_closed - self._eef_open)
        start = self.full[:, self.eef_ids].clone()
        for s in smooth_step(steps):
            self.full[:, self.eef_ids] = start + s * (goal - start)
            self._rows.append(self._row())

    def hold(self, steps: int) -> None:
        """Repeat the current targets for ``steps``."""
        self._rows += [self._row() for _ in range(steps)]

    # -- output ---------------------------------------------------------------------------
    def actions(self) -> list[torch.Tensor]:
        """The demo: one (num_envs, action_dim) float32 tensor per step, in the env's action
        space: the joint targets themselves without action terms, else what the env's
        ``pre`` action terms make of them (``ActionManager.action_from_qpos``: the TCP pose and
        the gripper targets for an ``EefPoseTerm``)."""
        manager = getattr(self.env, "action_manager", None)
        if manager is None or not manager.terms("pre"):
            return list(self._rows)
        return [manager.action_from_qpos(row) for row in self._rows]

    def __len__(self) -> int:
        return len(self._rows)

    def _append_arm(self, path: torch.Tensor) -> None:
        for q in path:
            self.arm_q = q
            self.full[:, self.arm_ids] = q
            self._rows.append(self._row())

    def _row(self) -> torch.Tensor:
        return self.full[:, self._active].to(torch.float32)


# -- scene pieces shared by the IL tasks ------------------------------------------------------
#: Torso crouch (ANKLE, KNEE, BUTTOCK, WAIST): shoulders 12 cm forward and 19 cm lower than
#: standing (arm bases at x 0.12, z 1.17), so the table top is inside both arms' workspace.
W1_CROUCH = (0.5, -1.5, 1.0, 0.0)
#: Head (NECK1, NECK2): looking 46 degrees down at the table.
W1_HEAD = (0.0, -0.55)
#: Right arm ready pose of PickFork: gripper pointing down 20 cm over the table at
#: (0.40, -0.22), fingers closing along y (an IK solution with wide joint-limit margins).
W1_RIGHT_READY_DOWN = (-0.373, -1.165, 0.191, 1.977, 2.572, -0.924, 0.408)


def w1_init_qpos(right_ready: Sequence[float] = W1_RIGHT_READY_DOWN) -> list[float]:
    """The 24 joint values (EmbodiChain breadth-first order) of the IL tasks' W1: crouched,
    head down, right arm at ``right_ready``, left arm its mirror image, grippers open."""
    qpos = list(W1_CROUCH) + list(W1_HEAD)
    for right in right_ready:
        qpos += [-right, right]  # LEFT_Jk, RIGHT_Jk interleaved; the left arm mirrors the right
    return [round(v, 4) for v in qpos] + [0.0] * 4


def w1_robot_cfg(right_ready: Sequence[float] = W1_RIGHT_READY_DOWN) -> Any:
    """DexforceW1 with industrial arms and DH PGC grippers, right arm at ``right_ready``
    (see docs/il_tasks.md)."""
    from embodichain_robots import DexforceW1Cfg

    fingers = "(LEFT|RIGHT)_FINGER[12]"
    return DexforceW1Cfg.from_dict(
        {
            "uid": "dexforce_w1",
            "version": "v021",
            "arm_kind": "industrial",
            "init_pos": [0.0, 0.0, 0.0],
            "init_qpos": w1_init_qpos(right_ready),
            "drive_pros": {"stiffness": {fingers: 3000.0}, "damping": {fingers: 100.0}, "max_effort": {fingers: 40.0}},
        }
    )


def il_sim_cfg() -> Any:
    """Simulation settings of the IL tasks: MuJoCo's elliptic friction cone (with
    :class:`tune_contacts`' ``impratio`` it keeps pinched objects from creeping)."""
    from embodichain_core.sim.cfg import PhysicsCfg, SimulationManagerCfg

    return SimulationManagerCfg(physics_config=PhysicsCfg(cone="elliptic"))


def eye_in_head_cfg(width: int = 320, height: int = 180) -> Any:
    """The seed tutorial's ``eye_in_head`` stereo camera at a data-generation resolution
    (the tutorial's 960x540 intrinsics scaled to ``width`` x ``height``), colour only."""
    from embodichain_sensors.cfg import StereoCameraCfg

    f = 450.0 * width / 960.0
    return StereoCameraCfg(
        uid="eye_in_head",
        width=width,
        height=height,
        left_to_right_pos=(0.06, 0.0, 0.0),
        intrinsics=(f, f, width / 2.0, height / 2.0),
        intrinsics_right=(f, f, width / 2.0, height / 2.0),
        extrinsics=StereoCameraCfg.ExtrinsicsCfg(parent="eyes"),
    )


def round_table_cfg() -> Any:
    """The seed tutorial's kinematic round table (top surface at z 0.82)."""
    from embodichain_core.sim.cfg import RigidBodyAttributesCfg, RigidObjectCfg
    from embodichain_core.sim.shapes import MeshCfg

    mesh = MeshCfg(fpath="CircleTableSimple/circle_table_simple.ply", compute_uv=True)
    return RigidObjectCfg(
        uid="table",
        shape=mesh,
        attrs=RigidBodyAttributesCfg(mass=10.0, static_friction=0.95),
        body_type="kinematic",
        init_pos=(0.80, 0.0, 0.8),
        init_rot=(0.0, 90.0, 0.0),
    )


#: Table top height over the table body origin (the slab's half thickness).
TABLE_TOP_OFFSET = 0.02


def point_light_cfg() -> Any:
    """The seed tutorial's point light (uid ``point``)."""
    from embodichain_core.sim.cfg import LightCfg

    return LightCfg(uid="point", light_type="point", color=(1.0, 1.0, 1.0), intensity=20.0, init_pos=(0.0, 0.0, 2.0))


def table_material_event() -> Any:
    """``randomize_visual_material`` of the table at every reset (the seed's textures)."""
    from embodichain_core.managers.cfg import EventCfg

    return EventCfg(
        func="randomize_visual_material",
        mode="reset",
        params={
            "entity_cfg": {"uid": "table"},
            "random_texture_prob": 0.5,
            "texture_path": "CocoBackground/coco",
            "base_color_range": [[0.2, 0.2, 0.2], [1.0, 1.0, 1.0]],
        },
    )


def light_event() -> Any:
    """``randomize_light`` on the ``point`` light at every reset."""
    from embodichain_core.managers.cfg import EventCfg

    return EventCfg(
        func="randomize_light",
        mode="reset",
        params={
            "entity_cfg": {"uid": "point"},
            "position_range": [[-0.5, -0.5, 1.8], [0.5, 0.5, 2.2]],
            "color_range": [[0.7, 0.7, 0.7], [1.0, 1.0, 1.0]],
            "intensity_range": [15.0, 30.0],
        },
    )


class tune_contacts(Functor):
    """Event functor (class) tuning contact settings before the scene compiles.

    MuJoCo's defaults let a thin object pinched on its 5 mm edges (a fork lying flat)
    creep and spin out of a parallel grasp. ``modify_scene`` raises the solver's
    ``impratio`` (the weight of friction against normal constraints; with the elliptic
    cone of ``physics_config`` it removes the creep) and can set ``condim`` and the
    friction of every collision geom of one entity. The event does nothing at run time
    (use ``mode: "startup"``).

    Args (params):
        impratio: MuJoCo's ``opt.impratio`` (None: keep 1).
        entity_cfg: ``{"uid": ...}`` of the entity whose geoms to tune (None: none).
        condim: contact dimensionality of those geoms: 1, 3, 4 or 6.
        friction: ``[sliding, torsional, rolling]`` coefficients of those geoms.

    Example:
        ``{"func": "embodichain_tasks.il.common:tune_contacts", "mode": "startup",
        "params": {"impratio": 20}}``
    """

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Write ``impratio`` and the geom contact settings into the spec."""
        import mujoco

        params, spec = cfg.params, scene.builder.spec
        if params.get("impratio") is not None:
            spec.option.impratio = float(params["impratio"])
        entity = params.get("entity_cfg")
        if entity is None:
            return
        uid = entity["uid"] if isinstance(entity, dict) else entity.uid
        root = spec.body(scene.builder.record(uid).root_body)
        for body in [root] + list(root.find_all(mujoco.mjtObj.mjOBJ_BODY)):
            for geom in body.geoms:
                if geom.contype or geom.conaffinity:
                    geom.condim = int(params.get("condim", geom.condim))
                    geom.friction = [float(v) for v in params.get("friction", geom.friction)]

    def __call__(self, env: Any, env_ids: Any, **params: Any) -> None:
        """Nothing to do at run time: the settings were compiled into the model."""
