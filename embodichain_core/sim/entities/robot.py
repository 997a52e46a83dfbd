"""Robots: articulations with control parts and proprioception."""

from __future__ import annotations

from typing import Any, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.articulation import Articulation
from embodichain_core.sim.entities.base import find_names
from embodichain_core.utils.math import pose_to_matrix
from embodichain_core.utils.suggest import did_you_mean


class Robot(Articulation):
    """The env's agent. ``control_parts`` map part names to joint ids.

    Example:
        >>> robot.get_joint_ids("left_arm")
        [6, 8, 10, 12, 14, 16, 18]
    """

    kind = "robot"

    def __init__(self, uid: str, cfg: Any, scene: Any, record: Any):
        super().__init__(uid, cfg, scene, record)
        self.control_parts: dict[str, list[int]] = {}
        for part, patterns in (cfg.control_parts or {}).items():
            ids, _ = find_names(self.joint_names, patterns, preserve_order=True, what="joint",
                                owner=f"{uid} control part {part!r}")
            self.control_parts[part] = ids
        self.solvers: dict[str, Any] = {}
        builder = getattr(cfg, "build_solvers", None)
        if callable(builder):
            self.solvers = builder(self) or {}

    def get_joint_ids(self, name: Optional[str] = None, remove_mimic: bool = False) -> list[int]:
        """Joint ids of control part ``name`` (all joints when ``None``)."""
        if name is None:
            ids = list(range(self.dof))
        elif name not in self.control_parts:
            raise KeyError(f"{self.uid}: unknown control part {name!r}.{did_you_mean(name, self.control_parts)}")
        else:
            ids = list(self.control_parts[name])
        if remove_mimic:
            ids = [i for i in ids if i not in self.mimic_ids]
        return ids

    @property
    def active_joint_ids(self) -> list[int]:
        """Joints that are not mimics."""
        return [i for i in range(self.dof) if i not in self.mimic_ids]

    def get_proprioception(self) -> dict[str, torch.Tensor]:
        """``{"qpos", "qvel", "qf"}``, each (N, dof)."""
        return {"qpos": self.get_qpos(), "qvel": self.get_qvel(), "qf": self.get_qf()}

    def get_link_names(self, name: Optional[str] = None) -> list[str]:
        """Links moved by control part ``name`` (all links when ``None``)."""
        if name is None:
            return list(self.link_names)
        model = self.scene.model
        jnt_bodies = {int(model.jnt_bodyid[self._joint_ids[j]]) for j in self.get_joint_ids(name)}
        return [n for n, b in zip(self.link_names, self.body_ids.tolist()) if b in jnt_bodies]

    def compute_fk(self, qpos: Optional[torch.Tensor] = None, link_names: Any = None,
                   env_ids: Any = None, to_matrix: bool = True) -> torch.Tensor:
        """Forward kinematics in the env frame for ``link_names`` at ``qpos`` (N, dof).

        Returns (n, L, 4, 4) (or (n, 4, 4) for one link name); ``qpos=None`` uses the
        current joint positions. Runs MuJoCo's kinematics on a scratch MjData per env,
        so the simulation state is untouched.
        """
        env = self._ids(env_ids)
        single = isinstance(link_names, str)
        links, _ = self.find_bodies(link_names if link_names is not None else self.link_names, preserve_order=True)
        bodies = self.body_ids[links].numpy()
        qpos = self.get_qpos()[env] if qpos is None else torch.as_tensor(qpos, dtype=torch.float64).reshape(len(env), -1)
        out = np.zeros((len(env), len(bodies), 7))
        data = mujoco.MjData(self.scene.model)
        adr = self.qpos_adr.numpy()
        for k, e in enumerate(env.tolist()):
            data.qpos[:] = self.sim.qpos[e].numpy()
            data.qpos[adr] = qpos[k].detach().cpu().numpy()
            mujoco.mj_kinematics(self.sim.get_model(e), data)
            out[k, :, :3], out[k, :, 3:] = data.xpos[bodies], data.xquat[bodies]
        pose = torch.as_tensor(out, dtype=torch.float32)
        pose = pose_to_matrix(pose) if to_matrix else pose
        return pose[:, 0] if single else pose
