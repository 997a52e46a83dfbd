"""W1 variant resolution: parse config values, derive control parts, TCPs and solvers."""

from __future__ import annotations

from enum import Enum
from typing import Any, Optional

import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean
from embodichain_robots.dexforce_w1 import params as P
from embodichain_robots.kinematics.solver import IKSolverCfg

SIDES = P.SIDES
Brand = P.DexforceW1HandBrand


def _enum(enum: type[Enum], value: Any, path: str, upper: bool = False) -> Any:
    text = str(getattr(value, "value", value)).strip()
    text = text.upper() if upper else text.lower()
    try:
        return enum(text)
    except ValueError:
        known = [e.value for e in enum]
        raise ConfigError(path, f"unknown value {value!r}.{did_you_mean(text, known)}") from None


def parse_version(value: Any) -> P.DexforceW1Version:
    """``"v021"``, ``"V025"`` or an enum -> :class:`DexforceW1Version`."""
    return _enum(P.DexforceW1Version, value, "version")


def parse_arm_kind(value: Any) -> P.DexforceW1ArmKind:
    """``"anthropomorphic"`` / ``"industrial"`` (case ignored)."""
    return _enum(P.DexforceW1ArmKind, value, "arm_kind")


def default_brand(arm_kind: Any) -> Brand:
    """BrainCo hands on anthropomorphic arms, DH_PGC_GRIPPER_M on industrial ones."""
    return Brand.DH_PGC_GRIPPER_M if parse_arm_kind(arm_kind) == P.DexforceW1ArmKind.INDUSTRIAL else Brand.BRAINCO_HAND


def _side(key: Any, path: str) -> str:
    side = str(getattr(key, "value", key)).strip().lower()
    if side not in SIDES:
        raise ConfigError(f"{path}.{key}", f"unknown side {key!r}; expected 'left' or 'right'")
    return side


def parse_hands(hand_types: dict) -> dict[str, Brand]:
    """``{side: brand}`` with sides and brands normalised; None values drop the side."""
    if not isinstance(hand_types, dict):
        raise ConfigError("hand_types", f"expected a {{side: brand}} mapping, got {hand_types!r}")
    return {
        _side(k, "hand_types"): _enum(Brand, v, f"hand_types.{k}", upper=True)
        for k, v in hand_types.items()
        if v is not None
    }


def parse_hand_versions(versions: Optional[dict]) -> Optional[dict]:
    """``{side: "v021"}`` (the only hand version)."""
    if versions is None:
        return None
    return {
        _side(k, "hand_versions"): _enum(P.DexforceW1HandVersion, v, f"hand_versions.{k}").value
        for k, v in versions.items()
    }


def parse_attach(xposes: Optional[dict]) -> Optional[dict]:
    """``{side: 4x4}`` as nested lists (validated shapes)."""
    if xposes is None:
        return None
    out = {}
    for key, value in xposes.items():
        mat = np.asarray(value, dtype=float)
        if mat.shape != (4, 4):
            raise ConfigError(f"hand_attach_xposes.{key}", f"expected a 4x4 matrix, got shape {mat.shape}")
        out[_side(key, "hand_attach_xposes")] = mat.tolist()
    return out


def eef_joints(side: str, brand: Brand) -> list[str]:
    """Control-part joints of a mounted end effector (no mimic joints)."""
    s = side.upper()
    if brand == Brand.BRAINCO_HAND:
        return [f"{s}_HAND_{f}" for f in ("THUMB1", "THUMB2", "INDEX", "MIDDLE", "RING", "PINKY")]
    if brand == Brand.DH_PGC_GRIPPER:
        return [f"{s}_FINGER1_JOINT", f"{s}_FINGER2_JOINT"]
    return [f"{s}_FINGER1", f"{s}_FINGER2"]


def control_parts(hand_types: dict) -> dict[str, list[str]]:
    """EmbodiChain's W1 control parts; ``{side}_eef`` only where a hand is mounted."""
    arm = {side: [f"{side.upper()}_J{i}" for i in range(1, 8)] for side in SIDES}
    parts = {
        "torso": ["ANKLE", "KNEE", "BUTTOCK", "WAIST"],
        "head": ["NECK1", "NECK2"],
        "left_arm": arm["left"],
        "right_arm": arm["right"],
        "dual_arm": arm["left"] + arm["right"],
    }
    for side, brand in parse_hands(hand_types).items():
        parts[f"{side}_eef"] = eef_joints(side, brand)
    parts["full_body"] = parts["torso"] + parts["head"] + arm["left"] + arm["right"]
    return parts


def default_tcp(side: str, version: Any, arm_kind: Any, brand: Optional[Brand]) -> np.ndarray:
    """4x4 TCP in ``{side}_ee``: by mounted brand (else arm kind), times the flange offset."""
    industrial = parse_arm_kind(arm_kind) == P.DexforceW1ArmKind.INDUSTRIAL
    if brand == Brand.BRAINCO_HAND or (brand is None and not industrial):
        tcp = np.array(P.TCP_BRAINCO[side], dtype=float)
    else:
        tcp = np.array(P.TCP_GRIPPER, dtype=float)
        tcp[2, 3] += 0.015 if brand == Brand.DH_PGC_GRIPPER else 0.0
    flange = np.eye(4)
    flange[2, 3] = P.EEF_FLANGE_OFFSET[parse_version(version)]
    return flange @ tcp


def default_solvers(version: Any, arm_kind: Any, hand_types: dict) -> dict[str, IKSolverCfg]:
    """One :class:`IKSolverCfg` per arm: ``{side}_arm_base`` -> ``{side}_ee`` with the TCP."""
    hands = parse_hands(hand_types)
    return {
        f"{side}_arm": IKSolverCfg(
            root_link_name=f"{side}_arm_base",
            end_link_name=f"{side}_ee",
            tcp=default_tcp(side, version, arm_kind, hands.get(side)).tolist(),
        )
        for side in SIDES
    }


def options(cfg: Any) -> Any:
    """:class:`W1Options` of a resolved :class:`DexforceW1Cfg`."""
    from embodichain_robots.dexforce_w1.model import W1Options

    tcps = {}
    for side in SIDES:
        solver = (cfg.solver_cfg or {}).get(f"{side}_arm")
        if solver is not None:
            tcp = solver.tcp if isinstance(solver, IKSolverCfg) else solver.get("tcp")
            tcps[side] = np.asarray(tcp, dtype=float).reshape(4, 4)
    attach = {k: np.asarray(v, dtype=float) for k, v in (cfg.hand_attach_xposes or {}).items()}
    return W1Options(
        version=parse_version(cfg.version),
        arm_kind=parse_arm_kind(cfg.arm_kind),
        hands=parse_hands(cfg.hand_types or {}),
        hand_attach=attach,
        tcps=tcps,
    )
