"""Batched serial-chain kinematics in torch, extracted from a compiled MjModel.

A chain from a root body to an end body is ``C_0 J_1(q_1) C_1 ... J_n(q_n) C_n``:
constant transforms ``C_i`` (body offsets, joint anchors) and joint motions
``J_i`` (a rotation about, or a translation along, a unit axis). FK and the
geometric Jacobian of a TCP are evaluated for a whole batch at once, in float64.

Example:
    >>> chain = SerialChain.from_model(model, "left_arm_base", "left_ee")
    >>> pose, jac = chain.jacobian(torch.zeros(64, 7), tip=torch.eye(4))
"""

from __future__ import annotations

from typing import NamedTuple, Optional, Sequence

import mujoco
import numpy as np
import torch

_F64 = torch.float64
_HINGE, _SLIDE = int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)


def _transform(pos: Sequence[float], quat: Sequence[float]) -> np.ndarray:
    out = np.eye(4)
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=float))
    out[:3, :3], out[:3, 3] = mat.reshape(3, 3), pos
    return out


def _translation(vec: Sequence[float]) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = vec
    return out


class _ChainConsts(NamedTuple):
    """The constant per-joint terms of a chain on one device."""

    base: torch.Tensor  # (4, 4) C_0
    next: torch.Tensor  # (n, 4, 4) C_i
    a: torch.Tensor  # (n, 4, 4) sin terms
    b: torch.Tensor  # (n, 4, 4) 1 - cos terms
    u: torch.Tensor  # (n, 4, 4) slide terms
    hinge_f: torch.Tensor  # (n,) 1.0 for hinges
    hinge: torch.Tensor  # (n,) True for hinges
    axes: torch.Tensor  # (n, 3) joint axes in their local frames
    limits: torch.Tensor  # (n, 2) joint limits


class SerialChain:
    """The kinematic chain of one control part.

    Attributes:
        joint_names: the chain's joint names (without the scene prefix), root to tip.
        axes: (n, 3) joint axes in their local frames.
        hinge: (n,) True for hinges, False for slides.
        limits: (n, 2) joint limits.
    """

    def __init__(
        self, consts: np.ndarray, axes: np.ndarray, hinge: np.ndarray, limits: np.ndarray, joint_names: Sequence[str]
    ):
        self.consts = torch.as_tensor(consts, dtype=_F64)
        self.axes = torch.as_tensor(axes, dtype=_F64)
        self.hinge = torch.as_tensor(hinge, dtype=torch.bool)
        self.limits = torch.as_tensor(limits, dtype=_F64)
        self.joint_names = list(joint_names)
        self._precompute()

    def _precompute(self) -> None:
        """Constant 4x4 terms of ``J_i(q) C_i = C + sin(q) A + (1 - cos(q)) B + q U``."""
        u, n = self.axes, len(self.joint_names)
        zero = torch.zeros_like(u[:, 0])
        k = torch.stack((zero, -u[:, 2], u[:, 1], u[:, 2], zero, -u[:, 0], -u[:, 1], u[:, 0], zero), -1)
        k = k.reshape(-1, 3, 3)  # cross-product matrices [u]x
        k4 = torch.zeros(n, 4, 4, dtype=_F64)
        k4[:, :3, :3] = k * self.hinge[:, None, None]
        nxt = self.consts[1:]
        self._a = k4 @ nxt
        self._b = k4 @ k4 @ nxt
        self._u = torch.zeros(n, 4, 4, dtype=_F64)
        slide = ~self.hinge
        self._u[slide, :3, 3] = u[slide]
        self._next = nxt
        self._hinge_f = self.hinge.to(_F64)
        self._all_hinges = bool(self.hinge.all())  # a constant, read once on the host
        host = _ChainConsts(
            self.consts[0], self._next, self._a, self._b, self._u, self._hinge_f, self.hinge, self.axes, self.limits
        )
        self._host = host
        self._on: dict[torch.device, _ChainConsts] = {}

    def on(self, device: torch.device) -> "_ChainConsts":
        """The chain's constant terms on ``device`` (copied there once, then cached; on the
        CPU the host tensors themselves, which a device audit tells apart from device ones)."""
        device = torch.device(device)
        if device.type == "cuda" and device.index is None:
            device = torch.device("cuda", torch.cuda.current_device())
        consts = self._on.get(device)
        if consts is None:
            consts = _ChainConsts(*(t.to(device) for t in self._host))
            self._on[device] = consts
        return consts

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    @classmethod
    def from_model(cls, model: mujoco.MjModel, root_body: str, end_body: str, prefix: str = "") -> "SerialChain":
        """The chain between two bodies of ``model`` (names without ``prefix``).

        Raises:
            ValueError: when ``end_body`` does not descend from ``root_body``, no
                joint lies between them, or a joint on the path is not a hinge or slide.
        """
        root = model.body(prefix + root_body).id
        body, path = model.body(prefix + end_body).id, []
        while body != root:
            if body == 0:
                raise ValueError(f"{end_body!r} is not a descendant of {root_body!r}")
            path.append(body)
            body = int(model.body_parentid[body])
        consts, axes, hinge, limits, names = [], [], [], [], []
        current = np.eye(4)
        for b in reversed(path):
            current = current @ _transform(model.body_pos[b], model.body_quat[b])
            for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
                kind = int(model.jnt_type[j])
                if kind not in (_HINGE, _SLIDE):
                    raise ValueError(f"joint {model.joint(j).name!r} on the chain is not a hinge or slide")
                anchor = model.jnt_pos[j]
                consts.append(current @ _translation(anchor))
                current = _translation(-anchor)
                axes.append(model.jnt_axis[j].copy())
                hinge.append(kind == _HINGE)
                limited = bool(model.jnt_limited[j])
                limits.append(model.jnt_range[j].copy() if limited else np.array([-np.inf, np.inf]))
                names.append(model.joint(j).name[len(prefix) :])
        if not names:
            raise ValueError(f"no joint between {root_body!r} and {end_body!r}")
        consts.append(current)
        return cls(np.stack(consts), np.stack(axes), np.array(hinge), np.stack(limits), names)

    # -- kinematics --------------------------------------------------------------------
    def joint_transforms(self, q: torch.Tensor) -> torch.Tensor:
        """(N, n, 4, 4) transforms ``J_i(q_i) C_i`` (joint motion, then the next offset)."""
        k = self.on(q.device)
        angle = q * k.hinge_f
        s, c = torch.sin(angle)[..., None, None], torch.cos(angle)[..., None, None]
        slide = (q * (1.0 - k.hinge_f))[..., None, None]
        return k.next + s * k.a + (1.0 - c) * k.b + slide * k.u

    def forward(
        self, q: torch.Tensor, tip: Optional[torch.Tensor] = None
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """FK with the joint frames.

        Returns:
            ``(pose, axes_w, origins)``: the tip pose (N, 4, 4) in the root frame,
            each joint's axis (N, n, 3) and origin (N, n, 3) in the root frame.
        """
        q = q.to(_F64)
        k = self.on(q.device)
        motion = self.joint_transforms(q)
        frame = k.base.expand(q.shape[0], 4, 4)
        frames = []
        for i in range(self.n):
            frames.append(frame)
            frame = frame @ motion[:, i]
        if tip is not None:
            frame = frame @ tip.to(_F64)
        stacked = torch.stack(frames, 1)
        axes_w = (stacked[..., :3, :3] @ k.axes[:, :, None])[..., 0]
        return frame, axes_w, stacked[..., :3, 3]

    def fk(self, q: torch.Tensor, tip: Optional[torch.Tensor] = None) -> torch.Tensor:
        """(N, 4, 4) pose of the end body (times ``tip``) in the root frame, float64.

        Computed where ``q`` is (CPU or an accelerator), with no host copy or sync;
        ``tip`` must be on that device too. The products are those of
        :meth:`forward`, in the same order (the same values on the CPU).
        """
        q = q.to(_F64)
        motion = self.joint_transforms(q)
        frame = self.on(q.device).base.expand(q.shape[0], 4, 4)
        for i in range(self.n):
            frame = frame @ motion[:, i]
        return frame if tip is None else frame @ tip.to(_F64)

    def jacobian(self, q: torch.Tensor, tip: Optional[torch.Tensor] = None) -> tuple[torch.Tensor, torch.Tensor]:
        """``(pose (N, 4, 4), J (N, 6, n))``: the geometric Jacobian (linear rows first),
        computed where ``q`` is (``tip`` on that device too), with no host read."""
        pose, axes_w, origins = self.forward(q, tip)
        k = self.on(q.device)
        lin = torch.linalg.cross(axes_w, pose[:, None, :3, 3] - origins, dim=-1)
        if not self._all_hinges:
            lin = torch.where(k.hinge[None, :, None], lin, axes_w)
        ang = axes_w * k.hinge_f[None, :, None]
        return pose, torch.cat((lin, ang), -1).transpose(1, 2)
