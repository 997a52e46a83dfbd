"""Rigid constraints toggled per env: MuJoCo weld equalities declared before compile."""

from __future__ import annotations

from typing import Any, Optional, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.sim.entities.rigid_object import RigidObject
from embodichain_core.utils.math import quat_conjugate, quat_mul, quat_rotate
from embodichain_core.managers.cfg import SceneEntityCfg

from embodichain_functors._common import ParamError, env_ids_of, validated
from embodichain_functors._functor import CheckedFunctor
from embodichain_functors._sim import pose7_from_matrix, write_model

__all__ = ["create_rigid_constraint", "remove_rigid_constraint", "weld_name"]


def weld_name(name: str) -> str:
    """The MuJoCo equality name of constraint ``name``."""
    return f"embodichain_functors/weld/{name}"


def _uid(cfg: Any) -> str:
    return cfg["uid"] if isinstance(cfg, dict) else cfg.uid


def _frame(local: Optional[Any]) -> torch.Tensor:
    """(7,) pose of a local frame given as 7 values, a 4x4 matrix or ``None`` (identity)."""
    if local is None:
        return torch.tensor([0.0, 0, 0, 1, 0, 0, 0], dtype=torch.float64)
    t = torch.as_tensor(np.asarray(local, dtype=np.float64))
    return pose7_from_matrix(t) if t.shape == (4, 4) else t.reshape(7)


def _relative(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Pose of ``b`` in the frame of ``a`` ((n, 7) each)."""
    qa_inv = quat_conjugate(a[:, 3:])
    return torch.cat((quat_rotate(qa_inv, b[:, :3] - a[:, :3]), quat_mul(qa_inv, b[:, 3:])), -1)


class create_rigid_constraint(CheckedFunctor):
    """Weld two rigid objects together in ``env_ids`` (typically a custom mode like ``"attach"``).

    The weld is declared (inactive) before the scene compiles; a call activates it
    per env. Without ``local_frame_b`` the objects are welded at their current
    relative pose; with local frames, ``local_frame_a`` (in ``a``) is held onto
    ``local_frame_b`` (in ``b``). A reset deactivates it (constraint state is
    part of each env's state); :func:`remove_rigid_constraint` releases it.

    Args (params):
        obj_a_cfg: the first rigid object.
        obj_b_cfg: the second rigid object.
        name: the constraint's name (for ``remove_rigid_constraint``).
        local_frame_a: frame on ``a``: 7 values (xyz, wxyz) or a 4x4 matrix.
        local_frame_b: frame on ``b``.

    Example:
        ``{"func": "create_rigid_constraint", "mode": "attach", "params": {"obj_a_cfg": {"uid": "plate"},
        "obj_b_cfg": {"uid": "cup"}, "name": "cup_on_plate"}}``
    """

    @classmethod
    def modify_scene(cls, cfg: Any, scene: Any) -> None:
        """Declare the (inactive) weld equality between the two bodies."""
        params = cfg.params
        spec = scene.builder.spec
        name = weld_name(str(params.get("name")))
        if any(e.name == name for e in spec.equalities):
            return
        for key in ("obj_a_cfg", "obj_b_cfg"):
            record = scene.builder.records.get(_uid(params[key]))
            if record is None or record.kind not in ("rigid_object", "background"):
                raise ParamError(cls.__name__, key, f"{_uid(params[key])!r} is not a rigid object")
        weld = spec.add_equality(
            name=name,
            type=mujoco.mjtEq.mjEQ_WELD,
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1=_uid(params["obj_a_cfg"]),
            name2=_uid(params["obj_b_cfg"]),
            active=False,
        )
        data = np.zeros(len(weld.data))
        data[10] = 1.0  # anchor 0, relpose from the initial poses, torquescale 1
        weld.data = data

    def check(
        self,
        env: Any,
        obj_a_cfg: Any = None,
        obj_b_cfg: Any = None,
        name: Any = None,
        local_frame_a: Any = None,
        local_frame_b: Any = None,
    ) -> None:
        functor = type(self).__name__
        for key, cfg in (("obj_a_cfg", obj_a_cfg), ("obj_b_cfg", obj_b_cfg)):
            if not isinstance(env.scene.get(_uid(cfg)), RigidObject):
                raise ParamError(functor, key, f"{_uid(cfg)!r} is not a rigid object")
        for key, frame in (("local_frame_a", local_frame_a), ("local_frame_b", local_frame_b)):
            if frame is not None and np.asarray(frame).shape not in ((7,), (4, 4)):
                raise ParamError(functor, key, f"expected 7 values or a 4x4 matrix, got {frame!r}")
        if not isinstance(name, str) or not name:
            raise ParamError(functor, "name", f"must be a non-empty string, got {name!r}")

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        obj_a_cfg: SceneEntityCfg,
        obj_b_cfg: SceneEntityCfg,
        name: str,
        local_frame_a: Optional[Sequence[float]] = None,
        local_frame_b: Optional[Sequence[float]] = None,
    ) -> None:
        ids = env_ids_of(env, env_ids)
        eq = mujoco.mj_name2id(env.scene.model, mujoco.mjtObj.mjOBJ_EQUALITY, weld_name(name))
        if local_frame_b is None:
            a = env.scene[obj_a_cfg.uid].get_local_pose()[ids].to(torch.float64)
            b = env.scene[obj_b_cfg.uid].get_local_pose()[ids].to(torch.float64)
            rel = _relative(a, b)
        else:  # T_b = T_a F_a F_b^-1
            fa, fb = _frame(local_frame_a)[None], _frame(local_frame_b)[None]
            rel = torch.cat(
                (
                    quat_rotate(fa[:, 3:], -quat_rotate(quat_conjugate(fb[:, 3:]), fb[:, :3])) + fa[:, :3],
                    quat_mul(fa[:, 3:], quat_conjugate(fb[:, 3:])),
                ),
                -1,
            ).expand(len(ids), 7)
        # no mj_setConst: it would recompute the relative pose from the initial configuration
        write_model(env.sim, ids, [("eq_data", (eq, slice(3, 10)), rel)], set_const=False)
        env.sim.eq_active[ids, eq] = 1.0
        env.sim.mark_dirty(ids)


def _check_remove(env: Any, name: Any) -> None:
    eq = mujoco.mj_name2id(env.scene.model, mujoco.mjtObj.mjOBJ_EQUALITY, weld_name(str(name)))
    if eq < 0:
        raise ParamError(
            "remove_rigid_constraint", "name", f"no rigid constraint {name!r}; declare it with create_rigid_constraint"
        )


@validated(_check_remove)
def remove_rigid_constraint(env: Any, env_ids: Any, name: str) -> None:
    """Release the rigid constraint ``name`` in ``env_ids`` (idempotent).

    Args:
        env: the env.
        env_ids: envs to release (``None``: all).
        name: the constraint's name, as given to ``create_rigid_constraint``.

    Example:
        ``{"func": "remove_rigid_constraint", "mode": "detach", "params": {"name": "cup_on_plate"}}``
    """
    ids = env_ids_of(env, env_ids)
    eq = mujoco.mj_name2id(env.scene.model, mujoco.mjtObj.mjOBJ_EQUALITY, weld_name(name))
    env.sim.eq_active[ids, eq] = 0.0
    env.sim.mark_dirty(ids)
