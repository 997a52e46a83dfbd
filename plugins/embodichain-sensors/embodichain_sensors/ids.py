"""Scene ids shared by the sensors: entity ids (masks) and actor names (contacts).

Every element an entity adds is named ``"<uid>"`` or ``"<uid>/<name>"`` (the
core's naming), so a geom belongs to the entity whose uid prefixes its own name,
its body's name or an ancestor body's name. The ground plane is
``"default_plane"``.

Entity ids are positions in :attr:`EntityIds.uids` (ordered like the scene's
entity records); ``-1`` means no entity (background or an unnamed world geom).
"""

from __future__ import annotations

from typing import Any, Iterable, Optional

import mujoco
import numpy as np

BACKGROUND_ID = -1


class EntityIds:
    """Geom -> entity id table of one compiled scene.

    Args:
        model: the compiled scene model.
        uids: entity uids, in id order.
    """

    def __init__(self, model: mujoco.MjModel, uids: Iterable[str]):
        self.uids: list[str] = list(uids)
        self._index = {uid: i for i, uid in enumerate(self.uids)}
        body_ids = np.array([self._owner_of_body(model, b) for b in range(model.nbody)], dtype=np.int32)
        geom_ids = np.empty(model.ngeom, dtype=np.int32)
        for g in range(model.ngeom):
            own = self.id_of_name(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g))
            geom_ids[g] = own if own is not None else body_ids[model.geom_bodyid[g]]
        self.body_to_id = body_ids
        self.geom_to_id = geom_ids

    @classmethod
    def from_scene(cls, scene: Any) -> "EntityIds":
        """The table of a built :class:`~embodichain_core.sim.scene.Scene`."""
        uids = [uid for uid, rec in scene.builder.records.items() if rec.kind != "sensor"]
        return cls(scene.model, uids)

    def id_of_name(self, name: Optional[str]) -> Optional[int]:
        """Entity id owning an element name (longest uid prefix), or ``None``."""
        if not name:
            return None
        if name in self._index:
            return self._index[name]
        parts = name.split("/")
        for k in range(len(parts) - 1, 0, -1):
            hit = self._index.get("/".join(parts[:k]))
            if hit is not None:
                return hit
        return None

    def _owner_of_body(self, model: mujoco.MjModel, body: int) -> int:
        while body > 0:
            own = self.id_of_name(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body))
            if own is not None:
                return own
            body = int(model.body_parentid[body])
        return BACKGROUND_ID

    def uid_of_id(self, entity_id: int) -> Optional[str]:
        """The uid of an entity id (``None`` for ``-1``)."""
        entity_id = int(entity_id)
        return self.uids[entity_id] if 0 <= entity_id < len(self.uids) else None

    def id_of_uid(self, uid: str) -> int:
        """The entity id of ``uid``."""
        if uid not in self._index:
            from embodichain_core.utils.suggest import did_you_mean

            raise KeyError(f"no entity {uid!r} in the mask table.{did_you_mean(uid, self.uids)}")
        return self._index[uid]

    def as_dict(self) -> dict[int, str]:
        """``{entity id: uid}``."""
        return dict(enumerate(self.uids))
