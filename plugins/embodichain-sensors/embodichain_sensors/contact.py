"""``ContactSensor``: active contacts of watched rigid objects and articulation links.

Per env the first ``K = max_contacts_per_env`` matching contacts (MuJoCo's order)
are reported; the rest of the ``K`` slots are zero with ``is_valid`` False.
Side 0 of a contact is a watched actor (the first listed when both are):

================  ==========================  ==============================================
key               dtype / shape               meaning
================  ==========================  ==============================================
``position``      float32 ``(N, K, 3)``       contact point, env frame
``normal``        float32 ``(N, K, 3)``       unit normal from side 1 into side 0
``force``         float32 ``(N, K, 3)``       contact force acting on side 0 (newtons)
``friction``      float32 ``(N, K, 3)``       tangential part of ``force``
``impulse``       float32 ``(N, K)``          normal force * physics_dt (N s)
``distance``      float32 ``(N, K)``          signed distance (< 0: penetration)
``user_ids``      int32 ``(N, K, 2)``         body ids of side 0 and side 1 (:meth:`actor_name`)
``is_valid``      bool ``(N, K)``             slot holds a contact
================  ==========================  ==============================================
"""

from __future__ import annotations

import re
from typing import Any

import mujoco
import numpy as np
import torch

from embodichain_core.sim.scene_build.builder import GROUND_UID
from embodichain_core.sim.sensor_base import BaseSensor
from embodichain_core.utils.suggest import did_you_mean
from embodichain_sensors.envs import EnvReader
from embodichain_sensors.ids import EntityIds

UNWATCHED = np.iinfo(np.int32).max


class ContactSensor(BaseSensor):
    """Contacts filtered by ``rigid_uid_list`` and ``articulation_cfg_list``."""

    def __init__(self, cfg: Any, scene: Any):
        super().__init__(cfg, scene)
        self.num_envs = int(scene.num_envs)
        self.max_contacts = int(cfg.max_contacts_per_env)
        self._rank = np.zeros(0, dtype=np.int64)
        self._force = np.zeros(6)
        self._data: dict[str, torch.Tensor] = {}
        self._envs = EnvReader(scene)

    # -- setup --------------------------------------------------------------------------------
    def bind(self) -> None:
        """Rank every geom: watched geoms get their actor's list position, others UNWATCHED."""
        model = self.scene.model
        rank = np.full(model.ngeom, UNWATCHED, dtype=np.int64)
        ids = EntityIds.from_scene(self.scene)
        for r, uid in enumerate(self.cfg.rigid_uid_list):
            if uid not in ids.uids:
                raise KeyError(f"contact sensor {self.uid!r}: no entity {uid!r}.{did_you_mean(uid, ids.uids)}")
            rank[(ids.geom_to_id == ids.id_of_uid(uid)) & (rank == UNWATCHED)] = r
        base = len(self.cfg.rigid_uid_list)
        for r, filt in enumerate(self.cfg.articulation_cfg_list):
            bodies = self._link_bodies(filt)
            rank[np.isin(model.geom_bodyid, bodies) & (rank == UNWATCHED)] = base + r
        self._watch_all = not self.cfg.rigid_uid_list and not self.cfg.articulation_cfg_list
        self._rank = rank
        self._names = [self._body_name(model, b) for b in range(model.nbody)]

    def _link_bodies(self, filt: Any) -> np.ndarray:
        arts = {**self.scene.articulations, **self.scene.robots}
        art = arts.get(filt.articulation_uid)
        if art is None:
            raise KeyError(
                f"contact sensor {self.uid!r}: no articulation {filt.articulation_uid!r}."
                f"{did_you_mean(filt.articulation_uid, arts)}"
            )
        if not filt.link_name_list:
            return art.body_ids.cpu().numpy()
        ids, _ = art.find_bodies(list(filt.link_name_list))
        return art.body_ids[ids].cpu().numpy()

    @staticmethod
    def _body_name(model: mujoco.MjModel, body: int) -> str:
        return GROUND_UID if body == 0 else (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or f"body{body}")

    # -- data -----------------------------------------------------------------------------------
    def update(self) -> None:
        """Collect the contacts of every env."""
        n, k = self.num_envs, self.max_contacts
        out = {
            "position": np.zeros((n, k, 3), np.float32),
            "normal": np.zeros((n, k, 3), np.float32),
            "force": np.zeros((n, k, 3), np.float32),
            "friction": np.zeros((n, k, 3), np.float32),
            "impulse": np.zeros((n, k), np.float32),
            "distance": np.zeros((n, k), np.float32),
            "user_ids": np.full((n, k, 2), -1, np.int32),
            "is_valid": np.zeros((n, k), bool),
        }
        for i in range(n):
            self._collect(self._envs.data(i), i, out)
        self._data = {key: torch.from_numpy(v) for key, v in out.items()}

    def _select(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """Indices of matching active contacts (at most K) and whether to swap sides."""
        con = data.contact
        ncon = int(data.ncon)
        if ncon == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool)
        geoms = np.asarray(con.geom)[:ncon]
        r1, r2 = self._rank[geoms[:, 0]], self._rank[geoms[:, 1]]
        active = (np.asarray(con.exclude)[:ncon] == 0) & (np.asarray(con.efc_address)[:ncon] >= 0)
        w1, w2 = r1 != UNWATCHED, r2 != UNWATCHED
        if self._watch_all:
            keep = active
        else:
            keep = active & ((w1 & w2) if self.cfg.filter_need_both_actor else (w1 | w2))
        idx = np.flatnonzero(keep)[: self.max_contacts]
        return idx, r2[idx] < r1[idx]

    def _collect(self, data: mujoco.MjData, i: int, out: dict[str, np.ndarray]) -> None:
        idx, swap = self._select(data)
        if len(idx) == 0:
            return
        model, con, dt = self.scene.model, data.contact, float(self.scene.sim_cfg.physics_dt)
        for slot, (c, s) in enumerate(zip(idx.tolist(), swap.tolist())):
            mujoco.mj_contactForce(model, data, c, self._force)
            frame = np.asarray(con.frame[c]).reshape(3, 3)
            sign = 1.0 if s else -1.0  # MuJoCo: force on geom2 along +normal (geom1 -> geom2)
            force = sign * (frame.T @ self._force[:3])
            normal = sign * frame[0]
            g0, g1 = (con.geom2[c], con.geom1[c]) if s else (con.geom1[c], con.geom2[c])
            out["position"][i, slot] = con.pos[c]
            out["normal"][i, slot] = normal
            out["force"][i, slot] = force
            out["friction"][i, slot] = force - np.dot(force, normal) * normal
            out["impulse"][i, slot] = abs(self._force[0]) * dt
            out["distance"][i, slot] = con.dist[c]
            out["user_ids"][i, slot] = (model.geom_bodyid[g0], model.geom_bodyid[g1])
            out["is_valid"][i, slot] = True

    def get_data(self) -> dict[str, torch.Tensor]:
        """``{name: tensor (N, K, ...)}`` of the last :meth:`update` (updating now if none)."""
        if not self._data:
            self.update()
        return self._data

    # -- names ----------------------------------------------------------------------------------------
    def actor_name(self, body_id: int) -> str:
        """Name of a ``user_ids`` value: ``"<uid>"``, ``"<uid>/<link>"`` or ``"default_plane"``."""
        return self._names[int(body_id)]

    def uid_of_actor(self, body_id: int) -> str:
        """The entity uid of a ``user_ids`` value."""
        name = self.actor_name(body_id)
        uids = list(self.scene.entities) + [GROUND_UID]
        hits = [u for u in uids if name == u or name.startswith(u + "/")]
        return max(hits, key=len) if hits else re.split("/", name)[0]
