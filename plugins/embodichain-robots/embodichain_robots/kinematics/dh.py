"""Standard-DH forward kinematics, batched (EmbodiChain's SRS solver convention).

Each row is ``Rz(theta0 + dir * q) . Tz(d) . Tx(a) . Rx(alpha)``; the full chain is
``T_b_ob . prod(rows) . T_e_oe``. Used as the reference the procedural W1 arms
are tested against.

Example:
    >>> pose = w1_arm_dh_fk(torch.zeros(1, 7), "left")   # {side}_ee in {side}_arm_base
"""

from __future__ import annotations

import math
from typing import Sequence

import torch

from embodichain_robots.dexforce_w1 import params as P


def dh_fk(
    q: torch.Tensor, rows: Sequence[Sequence[float]], directions: Sequence[float], base: torch.Tensor, tip: torch.Tensor
) -> torch.Tensor:
    """(N, 4, 4) poses of a DH chain at joint values ``q`` (N, n).

    Args:
        q: joint values.
        rows: per joint ``(d, alpha, a, theta0)``.
        directions: +1/-1 per joint (``rotation_directions``).
        base: 4x4 ``T_b_ob`` before the first row.
        tip: 4x4 ``T_e_oe`` after the last row.
    """
    q = torch.as_tensor(q, dtype=torch.float64)
    out = base.to(torch.float64).expand(q.shape[0], 4, 4).clone()
    for i, (d, alpha, a, theta0) in enumerate(rows):
        theta = theta0 + directions[i] * q[:, i]
        c, s = torch.cos(theta), torch.sin(theta)
        ca, sa = math.cos(alpha), math.sin(alpha)
        row = torch.zeros(q.shape[0], 4, 4, dtype=torch.float64)
        row[:, 0, 0], row[:, 0, 1], row[:, 0, 2], row[:, 0, 3] = c, -s * ca, s * sa, a * c
        row[:, 1, 0], row[:, 1, 1], row[:, 1, 2], row[:, 1, 3] = s, c * ca, -c * sa, a * s
        row[:, 2, 1], row[:, 2, 2], row[:, 2, 3] = sa, ca, d
        row[:, 3, 3] = 1.0
        out = out @ row
    return out @ tip.to(torch.float64)


def w1_arm_dh_fk(q: torch.Tensor, side: str, arm_kind: str = "anthropomorphic") -> torch.Tensor:
    """``{side}_ee`` in ``{side}_arm_base`` from EmbodiChain's W1 DH parameters."""
    kind = P.DexforceW1ArmKind(arm_kind)
    rows = [list(r) for r in P.DH_ROWS]
    if kind == P.DexforceW1ArmKind.INDUSTRIAL:
        rows[5][3] = 0.0
    base = torch.eye(4, dtype=torch.float64)
    base[2, 3] = P.ARM_BASE_Z
    tip = torch.tensor(P.T_E_OE[kind], dtype=torch.float64)
    return dh_fk(q, rows, P.ROTATION_DIRECTIONS[side], base, tip)
