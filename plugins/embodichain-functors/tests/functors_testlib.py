"""Helpers of the functor tests (a uniquely named module: test dirs share sys.path).

Small inline scenes for the functor tests.

``scene_cfg(**overrides)`` is a 4-env scene: the core's demo 7-DoF arm (control
part ``arm``), a dynamic cube and ball, a kinematic table, a point light. The
``build`` fixture makes envs from it (``build(events=..., ...)``) and closes them.
``apply(env, name_or_mode, ids)`` runs a custom event mode for some envs.
"""

from __future__ import annotations

import struct
import zlib
from typing import Any

import torch

from embodichain_core.demo.arm import ARM7_PATH
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers import EventCfg
from embodichain_core.sim.cfg import LightCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.shapes import CubeCfg, SphereCfg

N = 4
CUBE_POS = (0.5, 0.0, 0.025)
BALL_POS = (0.4, 0.25, 0.03)
TABLE_POS = (0.0, 0.8, 0.2)


def arm_cfg(**kwargs: Any) -> RobotCfg:
    """The demo arm with control part ``arm`` (joint1..7)."""
    return RobotCfg(uid="arm", fpath=str(ARM7_PATH), control_parts={"arm": ["joint[1-7]"]}, **kwargs)


def scene_cfg(**overrides: Any) -> EmbodiedEnvCfg:
    """The small test scene (see the module docstring) with ``overrides`` applied."""
    cfg = EmbodiedEnvCfg(
        num_envs=N,
        seed=0,
        verbose=False,
        robot=arm_cfg(),
        control_parts=["arm"],
        custom_event_modes=["test", "custom", "attach", "detach"],  # the modes the tests apply by hand
        rigid_object=[
            RigidObjectCfg(uid="cube", shape=CubeCfg(size=[0.05, 0.05, 0.05]), init_pos=CUBE_POS),
            RigidObjectCfg(uid="ball", shape=SphereCfg(radius=0.03), init_pos=BALL_POS),
        ],
        background=[
            RigidObjectCfg(uid="table", shape=CubeCfg(size=[0.4, 0.4, 0.4]), init_pos=TABLE_POS, body_type="kinematic")
        ],
        light=EmbodiedEnvCfg.EnvLightCfg(direct=[LightCfg(uid="point", init_pos=(0.0, 0.0, 2.0), intensity=20.0)]),
    )
    for key, value in overrides.items():
        if key not in cfg.__dataclass_fields__:
            raise AttributeError(f"EmbodiedEnvCfg has no field {key!r}")
        setattr(cfg, key, value)
    return cfg


def event(func: Any, mode: str = "test", **params: Any) -> dict:
    """An events section with one event ``ev`` in ``mode``."""
    return {"ev": EventCfg(func=func, mode=mode, params=params)}


def apply(env: EmbodiedEnv, ids: Any, mode: str = "test") -> torch.Tensor:
    """Run the events of ``mode`` for ``ids``; return the ids as a tensor."""
    ids = torch.as_tensor(ids, dtype=torch.long)
    env.event_manager.apply(mode, ids)
    return ids


def others(ids: Any) -> torch.Tensor:
    """The env ids not in ``ids``."""
    chosen = set(torch.as_tensor(ids).tolist())
    return torch.tensor([i for i in range(N) if i not in chosen], dtype=torch.long)


def field(env: EmbodiedEnv, name: str) -> torch.Tensor:
    """A copy of a per-env model field, (N, ...)."""
    import numpy as np

    return torch.as_tensor(np.array(env.sim.model_field(name)))


def write_png(path: str, rgb: tuple, size: int = 8) -> str:
    """A solid-colour RGB PNG (MuJoCo loads PNG textures)."""
    raw = b"".join(b"\x00" + bytes(rgb) * size for _ in range(size))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(
            b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
        )
    return path


def write_box_obj(path: str, half: tuple) -> str:
    """A box mesh (convex) as a Wavefront OBJ."""
    hx, hy, hz = half
    verts = [(x, y, z) for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)]
    faces = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]
    with open(path, "w") as f:
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in verts)
        for a, b, c, d in faces:
            f.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")
    return path


class ToySolver:
    """A fake kinematics solver for the ``arm`` part, in the core's solver protocol
    (``joint_ids``, ``root_link_name``, ``get_fk``, ``get_ik``); robot plugins
    (embodichain-robots) provide real ones.

    Its made-up chain puts the TCP at ``(q1, q2, q3)`` in the base frame with
    orientation ``rz(q4)``; IK inverts that exactly and fails for targets farther
    than 1 m from the base. ``calls`` records every IK request.
    """

    root_link_name = "base"

    def __init__(self, joint_ids: list[int]) -> None:
        self.joint_ids = list(joint_ids)
        self.calls: list[dict] = []

    def get_fk(self, qpos: torch.Tensor) -> torch.Tensor:
        from embodichain_core.utils.math import euler_xyz_to_quat, quat_to_matrix

        q = torch.as_tensor(qpos, dtype=torch.float64)
        pose = torch.eye(4, dtype=torch.float64).repeat(q.shape[0], 1, 1)
        pose[:, :3, 3] = q[:, :3]
        yaw = torch.zeros(q.shape[0], 3, dtype=torch.float64)
        yaw[:, 2] = q[:, 3]
        pose[:, :3, :3] = quat_to_matrix(euler_xyz_to_quat(yaw, degrees=False))
        return pose

    def get_ik(self, target: torch.Tensor, qpos_seed: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        target = torch.as_tensor(target, dtype=torch.float64)
        self.calls.append({"target": target.clone(), "seed": torch.as_tensor(qpos_seed).clone()})
        q = torch.as_tensor(qpos_seed, dtype=torch.float64).clone()
        q[:, :3] = target[:, :3, 3]
        q[:, 3] = torch.atan2(target[:, 1, 0], target[:, 0, 0])
        return target[:, :3, 3].norm(dim=-1) <= 1.0, q


def toy_ik_arm_cfg(parts: dict | None = None, **kwargs: Any) -> RobotCfg:
    """The demo arm whose config builds a :class:`ToySolver` for part ``arm`` (its control
    parts: ``parts``, default ``arm`` = all seven joints)."""
    from embodichain_core.utils.configclass import configclass

    @configclass
    class ToyIKArmCfg(RobotCfg):
        def build_solvers(self, robot: Any) -> dict:
            return {"arm": ToySolver(robot.get_joint_ids("arm"))}

    return ToyIKArmCfg(uid="arm", fpath=str(ARM7_PATH), control_parts=parts or {"arm": ["joint[1-7]"]}, **kwargs)
