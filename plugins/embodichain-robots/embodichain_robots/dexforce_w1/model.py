"""Assemble the procedural W1 ``MjSpec`` from :mod:`params` and the part builders.

Body declaration order (waist: neck1, left arm, right arm; hands: index, middle,
ring, pinky, thumb) makes the breadth-first joint order EmbodiChain's:
``ANKLE, KNEE, BUTTOCK, WAIST, NECK1, NECK2, L_J1, R_J1, ..., L_J7, R_J7``, then
the hands.

Example:
    >>> spec = build_w1_spec(W1Options())
    >>> spec.compile().njnt
    40
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import mujoco
import numpy as np

from embodichain_core.utils.math import matrix_to_quat
from embodichain_robots.dexforce_w1 import params as P
from embodichain_robots.dexforce_w1.arm import build_arm
from embodichain_robots.dexforce_w1.body import build_chassis, build_head, build_torso
from embodichain_robots.dexforce_w1.eef import build_eef
from embodichain_robots.spec_utils import new_spec


@dataclass
class W1Options:
    """Generator switches resolved from :class:`DexforceW1Cfg`.

    Attributes:
        version: hardware version (flange offset).
        arm_kind: anthropomorphic or industrial arms.
        hands: side -> mounted brand, or None for a bare flange.
        hand_attach: side -> 4x4 mount in the ee frame (before the flange offset).
        tcps: side -> 4x4 TCP in the ee frame (flange offset included), for the
            ``{side}_tcp`` sites.
    """

    version: P.DexforceW1Version = P.DexforceW1Version.V021
    arm_kind: P.DexforceW1ArmKind = P.DexforceW1ArmKind.ANTHROPOMORPHIC
    hands: dict = field(default_factory=lambda: {s: P.DexforceW1HandBrand.BRAINCO_HAND for s in P.SIDES})
    hand_attach: dict = field(default_factory=dict)
    tcps: dict = field(default_factory=dict)

    def flange(self) -> np.ndarray:
        """The version flange offset as a 4x4 (translation along ee z)."""
        out = np.eye(4)
        out[2, 3] = P.EEF_FLANGE_OFFSET[self.version]
        return out


def build_w1_spec(opts: Optional[W1Options] = None) -> mujoco.MjSpec:
    """The W1 as an ``MjSpec`` (no actuators: the core adds the drives)."""
    opts = opts or W1Options()
    spec = new_spec(f"dexforce_w1_{opts.version.value}")
    base = build_chassis(spec.worldbody)
    waist = build_torso(base)
    build_head(waist)
    ees = {side: build_arm(waist, side, opts.arm_kind) for side in P.SIDES}
    for side, ee in ees.items():
        _add_tcp_site(ee, side, opts.tcps.get(side))
        brand = opts.hands.get(side)
        if brand is not None:
            attach = opts.hand_attach.get(side)
            mount = opts.flange() @ (np.eye(4) if attach is None else np.asarray(attach, dtype=float))
            build_eef(spec, ee, side, brand, mount)
    return spec


def _add_tcp_site(ee: mujoco.MjsBody, side: str, tcp: Optional[np.ndarray]) -> None:
    if tcp is None:
        return
    tcp = np.asarray(tcp, dtype=float)
    ee.add_site(
        name=f"{side}_tcp",
        pos=tcp[:3, 3].tolist(),
        quat=matrix_to_quat(tcp[:3, :3]).tolist(),
        size=[0.008, 0, 0],
        rgba=[0.1, 0.8, 0.2, 0.6],
        group=4,
    )
