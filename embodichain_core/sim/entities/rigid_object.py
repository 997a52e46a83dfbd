"""Rigid objects (dynamic: free joint; kinematic/static: mocap body), batched."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.base import Entity, StateSlices, as_array, as_values
from embodichain_core.utils.math import (
    as_pose7,
    init_pos_from_cfg,
    init_quat_from_cfg,
    pose_to_matrix,
    quat_rotate,
)


class RigidObject(Entity):
    """One rigid body per env.

    Poses are ``(N, 7)`` xyz + wxyz in the env frame (or ``(N, 4, 4)`` with
    ``to_matrix=True``); velocities are world-frame ``(N, 6)`` linear + angular.

    Example:
        >>> cube = env.scene["cube"]
        >>> cube.set_local_pose(torch.tensor([[0.5, 0, 0.1, 1, 0, 0, 0]]), env_ids=[0])
        >>> cube.get_local_pose().shape
        torch.Size([N, 7])
    """

    kind = "rigid_object"
    state_only_reset = True

    def __init__(self, uid: str, cfg: Any, scene: Any, body: str | None = None, parts: dict | None = None):
        super().__init__(uid, cfg, scene)
        model = scene.model
        self.body_id = self._name2id(mujoco.mjtObj.mjOBJ_BODY, body or uid)
        self.is_dynamic = cfg.body_type == "dynamic"
        parts = parts or {}
        self.geom_ids = [self._name2id(mujoco.mjtObj.mjOBJ_GEOM, g) for g in parts.get("collision_geoms", [])]
        self.visual_geom_ids = [self._name2id(mujoco.mjtObj.mjOBJ_GEOM, g) for g in parts.get("visual_geoms", [])]
        self.material_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, parts.get("material", ""))
        if self.is_dynamic:
            jid = model.body_jntadr[self.body_id]
            self.qpos_adr = int(model.jnt_qposadr[jid])
            self.dof_adr = int(model.jnt_dofadr[jid])
        else:
            self.mocap_id = int(model.body_mocapid[self.body_id])
        self.init_pose = torch.as_tensor(
            np.concatenate(
                [
                    init_pos_from_cfg(cfg.init_pos, cfg.init_local_pose),
                    init_quat_from_cfg(cfg.init_rot, cfg.init_local_pose),
                ]
            ),
            dtype=torch.float64,
        )
        self.default_mass = float(model.body_mass[self.body_id])

    @property
    def body_scale(self) -> torch.Tensor:
        """(N, 3) scale applied to the shape."""
        return torch.as_tensor(self.cfg.body_scale, dtype=torch.float32).expand(self.num_envs, 3).clone()

    # -- pose ------------------------------------------------------------------------------
    def get_local_pose(self, to_matrix: bool = False) -> torch.Tensor:
        """Pose in the env frame, ``(N, 7)`` or ``(N, 4, 4)``."""
        if self.is_dynamic:
            pose = self.state_route.rows("qpos", (slice(None), slice(self.qpos_adr, self.qpos_adr + 7)))
        else:
            pose = self.state_route.pose("mocap_pos", "mocap_quat", (slice(None), self.mocap_id))
        return pose_to_matrix(pose) if to_matrix else pose

    def set_local_pose(self, pose: Any, env_ids: Any = None) -> None:
        """Teleport ``env_ids`` to ``pose`` ((n, 7) or (n, 4, 4); tensor or array)."""
        ids = self._ids(env_ids)
        if isinstance(pose, np.ndarray) and pose.shape == (len(ids), 7):
            pose7 = pose
        else:
            pose7 = as_values(as_pose7(torch.as_tensor(pose, dtype=torch.float64)), len(ids), 7).numpy()
        quat = pose7[:, 3:]
        quat = quat / np.maximum(np.sqrt(np.einsum("ij,ij->i", quat, quat)), 1e-12)[:, None]
        rows, route = ids.numpy(), self.state_route
        if self.is_dynamic:
            route.write("qpos", (rows, slice(self.qpos_adr, self.qpos_adr + 3)), pose7[:, :3])
            route.write("qpos", (rows, slice(self.qpos_adr + 3, self.qpos_adr + 7)), quat)
        else:
            route.write("mocap_pos", (rows, self.mocap_id), pose7[:, :3])
            route.write("mocap_quat", (rows, self.mocap_id), quat)
        self.sim.mark_dirty(rows)

    # -- velocity --------------------------------------------------------------------------
    def get_velocity(self) -> torch.Tensor:
        """World-frame ``(N, 6)`` linear and angular velocity (zeros for kinematic)."""
        if not self.is_dynamic:
            return torch.zeros(self.num_envs, 6, device=self.device)
        qvel = self.sim.qvel[:, self.dof_adr : self.dof_adr + 6]
        quat = self.sim.qpos[:, self.qpos_adr + 3 : self.qpos_adr + 7]
        ang = quat_rotate(quat, qvel[:, 3:])
        return self._out(torch.cat((qvel[:, :3], ang), dim=-1))

    def get_linear_velocity(self) -> torch.Tensor:
        return self.get_velocity()[:, :3]

    def get_angular_velocity(self) -> torch.Tensor:
        return self.get_velocity()[:, 3:]

    def set_velocity(self, velocity: torch.Tensor, env_ids: Any = None) -> None:
        """Set world-frame ``(n, 6)`` velocities of dynamic objects."""
        if not self.is_dynamic:
            return
        ids = self._ids(env_ids)
        rows, vel, route = ids.numpy(), as_array(velocity, len(ids), 6), self.state_route
        route.write("qvel", (rows, slice(self.dof_adr, self.dof_adr + 3)), vel[:, :3])
        angular = vel[:, 3:]
        if np.count_nonzero(angular):  # a push (no spin) needs no rotation into the body frames
            quat = route.read("qpos", (rows, slice(self.qpos_adr + 3, self.qpos_adr + 7)))
            angular = _rotate_inverse(quat, angular)
        route.write("qvel", (rows, slice(self.dof_adr + 3, self.dof_adr + 6)), angular)
        self.sim.mark_dirty(rows)

    def clear_dynamics(self, env_ids: Any = None) -> None:
        """Zero velocities and applied wrenches of ``env_ids``."""
        rows = self._ids(env_ids).numpy()
        if self.is_dynamic:
            self.state_route.write("qvel", (rows, slice(self.dof_adr, self.dof_adr + 6)), 0.0)
        self.state_route.write("xfrc_applied", (rows, self.body_id), 0.0)
        self.sim.mark_dirty(rows)

    # -- physical attributes -----------------------------------------------------------------
    def get_mass(self) -> torch.Tensor:
        """(N,) body masses."""
        return self._out(self.sim.model_tensor("body_mass")[:, self.body_id])

    def set_mass(self, mass: Any, env_ids: Any = None) -> None:
        """Set per-env masses; inertia scales with the mass (same density distribution)."""
        ids = self._ids(env_ids)
        mass = as_values(mass, len(ids)).numpy()
        if (mass <= 0).any():
            raise ValueError(f"{self.uid}: masses must be > 0, got {mass.min()}")
        self.sim.set_body_masses(ids, [self.body_id], mass[:, None])

    def get_com(self) -> torch.Tensor:
        """(N, 3) centre of mass in the body frame."""
        return self._out(self.sim.model_tensor("body_ipos")[:, self.body_id])

    def set_com(self, com: Any, env_ids: Any = None) -> None:
        ids = self._ids(env_ids)
        self.sim.set_model_field("body_ipos", ids, self.body_id, as_values(com, len(ids), 3).numpy())

    def get_friction(self) -> torch.Tensor:
        """(N,) sliding friction of the collision geoms (first geom)."""
        gid = self.geom_ids[0] if self.geom_ids else self.visual_geom_ids[0]
        return self._out(self.sim.model_tensor("geom_friction")[:, gid, 0])

    def set_friction(self, friction: Any, env_ids: Any = None) -> None:
        ids = self._ids(env_ids)
        vals = as_values(friction, len(ids)).numpy()
        for gid in self.geom_ids:
            self.sim.set_model_field("geom_friction", ids, (gid, 0), vals)

    def set_color(self, rgba: Any, env_ids: Any = None) -> None:
        """Per-env base colour (RGBA) of the object's material."""
        ids = self._ids(env_ids)
        self.sim.set_model_field("mat_rgba", ids, self.material_id, as_values(rgba, len(ids), 4).numpy())

    # -- reset -----------------------------------------------------------------------------------
    def state_slices(self) -> StateSlices:
        if self.is_dynamic:
            return StateSlices(
                qpos=list(range(self.qpos_adr, self.qpos_adr + 7)), qvel=list(range(self.dof_adr, self.dof_adr + 6))
            )
        return StateSlices(mocap=[self.mocap_id])

    def initial_state(self) -> list[np.ndarray]:
        return [self.init_pose.numpy()]

    def reset(self, env_ids: Any = None) -> None:
        """Back to ``init_pose`` at rest (no applied wrench)."""
        ids = self._ids(env_ids)
        self.set_local_pose(self.init_pose.expand(len(ids), 7), ids)
        self.clear_dynamics(ids)


def _rotate_inverse(quat: np.ndarray, vec: np.ndarray) -> np.ndarray:
    """Rotate (n, 3) world vectors into the frames of (n, 4) unit wxyz quaternions."""
    w, u = quat[:, :1], -quat[:, 1:]  # the conjugate rotation
    t = 2.0 * _cross(u, vec)
    return vec + w * t + _cross(u, t)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) arrays."""
    out = np.empty_like(b)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out
