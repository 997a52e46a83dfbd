"""Manager sections of an env config, checked before the scene is built.

Each manager owns the rules of its section (``validate_section`` of
:class:`~embodichain_core.managers.manager_base.ManagerBase` and its subclasses); this
module runs them over a config, with the uids of the scene the config describes.
"""

from __future__ import annotations

from typing import Any

from embodichain_core.config.checks import describe
from embodichain_core.config.errors import ConfigError, join_path

__all__ = ["check_sections", "scene_uids"]


def check_sections(cfg: Any, warn: bool = False) -> dict[str, dict[str, Any]]:
    """Check every functor entry of the manager sections of ``cfg`` (an ``EmbodiedEnvCfg``).

    Args:
        cfg: the env config.
        warn: warn about valid values that look like mistakes (an interval event that
            never fires); the env's build passes ``True``.

    Returns:
        ``{section: {name: ValidatedFunctor}}``: each functor resolved once, as the env
        builds its scene and managers from them.

    Raises:
        ConfigError: at the config path of the first bad value.
    """
    from embodichain_core.managers import (
        ActionManager,
        DatasetManager,
        EventManager,
        ObservationManager,
        RewardManager,
    )

    uids = scene_uids(cfg)
    managers = (EventManager, ObservationManager, RewardManager, ActionManager, DatasetManager)
    return {m.section: m.validate_section(cfg, uids=uids, warn=warn) for m in managers}


def scene_uids(cfg: Any) -> list[str]:
    """Every uid the config's scene will have (the ground plane included); uids must be
    unique, non-empty and free of ``/`` (group members are named ``<group>/<member>``)."""
    from embodichain_core.sim.scene_build.builder import GROUND_UID

    entries = [("robot", getattr(cfg.robot, "uid", None) or "robot")]
    for key in ("articulation", "articulation_cfg", "background", "rigid_object", "rigid_object_group", "sensor"):
        entries += [(f"{key}[{i}]", obj.uid) for i, obj in enumerate(getattr(cfg, key))]
    entries += [(f"light.direct[{i}]", light.uid) for i, light in enumerate(cfg.light.direct)]
    seen: dict[str, str] = {GROUND_UID: "the ground plane"}
    for path, uid in entries:
        where = join_path(path, "uid")
        if not isinstance(uid, str) or not uid or "/" in uid:
            raise ConfigError(where, f"expected a non-empty uid without '/', got {describe(uid)}")
        if uid in seen:
            raise ConfigError(where, f"uid {uid!r} is already used by {seen[uid]}; uids must be unique")
        seen[uid] = path
    return list(seen)
