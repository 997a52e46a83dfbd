"""Where a camera is mounted: the env frame, a body (robot link) or a site.

``parent`` names are resolved on the scene spec before compile:

* an exact body name (``"table"``, ``"dexforce_w1/eyes"``, a ``"<robot uid>/<link>"``);
* a partial name: the trailing ``/``-separated parts of one full name (``"gripper_link"`` or
  ``"vx300s_left/gripper_link"`` for ``"arm/vx300s_left/gripper_link"``; never a substring
  within a part). When several full names end that way, the robot's are kept; more than one
  left is an error listing them;
* the same for sites (the camera is fixed to the site's body at the site's pose).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

import mujoco
import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.math import quat_normalize, quat_to_matrix
from embodichain_core.utils.suggest import did_you_mean


@dataclass
class Mount:
    """A resolved parent: ``body`` (spec name, ``None`` for the env frame) and the
    pose of the parent frame in that body (identity for a body, the site's pose)."""

    body: Optional[str] = None
    pos: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rot: np.ndarray = field(default_factory=lambda: np.eye(3))
    body_id: int = 0

    def bind(self, model: mujoco.MjModel) -> None:
        """Look the body up in the compiled model (world body for the env frame)."""
        self.body_id = 0 if self.body is None else mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, self.body)
        if self.body_id < 0:
            raise RuntimeError(f"mount body {self.body!r} is not in the compiled model")

    def body_poses(self, sim: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(N, 3)`` positions and ``(N, 3, 3)`` rotations of the mount frame in each env."""
        xpos = sim.xpos[:, self.body_id].detach().cpu().numpy()  # a few floats per env, also from a GPU
        xmat = sim.xmat[:, self.body_id].detach().cpu().numpy().reshape(-1, 3, 3)
        if self.body is None or (not self.pos.any() and np.array_equal(self.rot, np.eye(3))):
            return xpos, xmat
        return xpos + xmat @ self.pos, xmat @ self.rot


def resolve_mount(spec: mujoco.MjSpec, parent: Optional[str], records: dict, where: str) -> Mount:
    """Resolve ``parent`` on ``spec`` (see the module docstring).

    Args:
        spec: the scene spec (entities added before the sensor are in it).
        parent: the configured parent name or ``None``.
        records: the builder's entity records (to prefer robots).
        where: config path for errors.
    """
    if parent is None:
        return Mount()
    bodies = [b.name for b in spec.bodies if b.name]
    body = _match(parent, bodies, records, where)
    if body is not None:
        return Mount(body=body)
    sites = {s.name: s for s in spec.sites if s.name}
    site = _match(parent, list(sites), records, where)
    if site is not None:
        s = sites[site]
        rot = quat_to_matrix(quat_normalize(np.asarray(s.quat, dtype=np.float64)))
        return Mount(body=s.parent.name or None, pos=np.asarray(s.pos, dtype=np.float64), rot=rot)
    links = [b for b in bodies if "/" in b]
    raise ConfigError(where, f"no link, body or site named {parent!r} in the scene.{did_you_mean(parent, links)}")


def _match(name: str, names: list[str], records: dict, where: str) -> Optional[str]:
    if name in names:
        return name
    hits = [n for n in names if n.endswith("/" + name)]
    if len(hits) > 1:
        robots = [n for n in hits if getattr(records.get(n.split("/", 1)[0]), "kind", "") == "robot"]
        hits = robots or hits
    if len(hits) > 1:
        listed = ", ".join(repr(h) for h in sorted(hits))
        raise ConfigError(
            where, f"partial name {name!r} is ambiguous: {len(hits)} names end with it ({listed}); give one in full"
        )
    return hits[0] if hits else None
