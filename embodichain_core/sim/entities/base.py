"""Common plumbing of scene entities: env-id handling, name lookup and the state route.

Every entity reads and writes the simulation's state through ``self.state_route``, the
:class:`~embodichain_core.sim.backend.state_route.StateRoute` chosen once when it binds to
the simulation (numpy views on a backend with host arrays, torch views otherwise)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import mujoco
import numpy as np
import torch

from embodichain_core.sim.backend.state_route import StateRoute, state_route
from embodichain_core.utils.suggest import did_you_mean

if TYPE_CHECKING:
    from embodichain_core.sim.scene import Scene


def env_index(env_ids: Any, num_envs: int) -> torch.Tensor:
    """Normalize ``env_ids`` (None, slice, list, array, tensor, bool mask) to a long tensor."""
    if isinstance(env_ids, torch.Tensor) and env_ids.dtype == torch.long and env_ids.dim() == 1:
        return env_ids  # already normalized (the hot path: managers pass these on)
    if env_ids is None or (isinstance(env_ids, slice) and env_ids == slice(None)):
        return torch.arange(num_envs)
    if isinstance(env_ids, slice):
        return torch.arange(num_envs)[env_ids]
    t = torch.as_tensor(env_ids)
    if t.dtype == torch.bool:
        return torch.nonzero(t).flatten()
    return t.reshape(-1).long()


def find_names(
    names: Sequence[str], patterns: Any, preserve_order: bool = False, what: str = "name", owner: str = ""
) -> tuple[list[int], list[str]]:
    """Match regex ``patterns`` (full match) against ``names``; return ids and names.

    Unmatched patterns raise ``KeyError`` naming the owner and the closest names.
    """
    if isinstance(patterns, str):
        patterns = [patterns]
    hits: list[int] = []
    for pattern in patterns:
        matched = [i for i, n in enumerate(names) if n == pattern or re.fullmatch(pattern, n)]
        if not matched:
            raise KeyError(f"{owner}: no {what} matches {pattern!r}.{did_you_mean(pattern, names)}")
        hits += [i for i in matched if i not in hits]
    if not preserve_order:
        hits = sorted(hits)
    return hits, [names[i] for i in hits]


@dataclass
class StateSlices:
    """The state columns an entity owns: indices into ``sim.qpos``, ``sim.qvel`` and
    ``sim.ctrl``, and its mocap body ids (rows of ``sim.mocap_pos``/``mocap_quat``)."""

    qpos: list[int] = field(default_factory=list)
    qvel: list[int] = field(default_factory=list)
    ctrl: list[int] = field(default_factory=list)
    mocap: list[int] = field(default_factory=list)

    def __add__(self, other: "StateSlices") -> "StateSlices":
        return StateSlices(
            self.qpos + other.qpos, self.qvel + other.qvel, self.ctrl + other.ctrl, self.mocap + other.mocap
        )


class Entity:
    """Base of every scene entity: ``uid``, ``cfg``, the scene and its batch.

    What a scene reset needs from an entity it declares itself: the state columns it
    owns (:meth:`state_slices`), whether its :meth:`reset` only writes those columns
    (:attr:`state_only_reset`) and from which values (:meth:`initial_state`).
    """

    kind = "entity"
    state_only_reset: bool = False
    """Whether :meth:`reset` writes nothing but the entity's :meth:`state_slices` of the
    state rows (plus zero velocities and applied forces), from :meth:`initial_state`.
    Then a scene reset that restores the saved default row
    (:mod:`embodichain_core.sim.scene_defaults`) skips it. A subclass that overrides
    ``reset`` without declaring this again is not state-only."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "reset" in cls.__dict__ and "state_only_reset" not in cls.__dict__:
            cls.state_only_reset = False  # a new reset may do more than the saved row holds

    def __init__(self, uid: str, cfg: Any, scene: "Scene"):
        self.uid = uid
        self.cfg = cfg
        self.scene = scene
        self.state_route: StateRoute = state_route(scene.sim, scene.device)
        """How this entity reads and writes the simulation's state (chosen here, once)."""

    @property
    def sim(self):
        return self.scene.sim

    @property
    def num_envs(self) -> int:
        return self.scene.num_envs

    @property
    def device(self) -> torch.device:
        return self.scene.device

    def _ids(self, env_ids: Any) -> torch.Tensor:
        return env_index(env_ids, self.num_envs)

    def _name2id(self, obj: mujoco.mjtObj, name: str) -> int:
        idx = mujoco.mj_name2id(self.scene.model, obj, name)
        if idx < 0:
            raise KeyError(f"{self.uid}: no MuJoCo element {name!r}")
        return idx

    def _out(self, t: torch.Tensor) -> torch.Tensor:
        return t.to(dtype=torch.float32, device=self.device)

    def state_slices(self) -> StateSlices:
        """The state columns this entity owns (kept as they are by a scene reset that
        keeps the entity, see :meth:`~embodichain_core.sim.scene.Scene.reset`)."""
        return StateSlices()

    def initial_state(self) -> list[np.ndarray]:
        """Every value a state-only :meth:`reset` reads besides the model (the saved
        default row is dropped as soon as one of them changes)."""
        return []

    def reset(self, env_ids: Any = None) -> None:
        """Restore the configured initial state of ``env_ids``."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(uid={self.uid!r})"


def as_values(values: Any, n: int, width: int | None = None) -> torch.Tensor:
    """Values as a float64 CPU tensor broadcast to (n, width) or (n,)."""
    shape = (n,) if width is None else (n, width)
    if (
        isinstance(values, torch.Tensor)
        and values.dtype == torch.float64
        and values.shape == shape
        and values.device.type == "cpu"
    ):
        return values.detach()
    t = torch.as_tensor(np.asarray(values) if not isinstance(values, torch.Tensor) else values)
    t = t.detach().to("cpu", torch.float64)
    return torch.broadcast_to(t, shape)


def as_array(values: Any, n: int, width: int | None = None) -> np.ndarray:
    """Values as a float64 numpy array broadcast to (n, width) or (n,) (read-only when broadcast)."""
    shape = (n,) if width is None else (n, width)
    if isinstance(values, torch.Tensor):
        values = values.detach().cpu().numpy()
    arr = np.asarray(values, dtype=np.float64)
    return arr if arr.shape == shape else np.broadcast_to(arr, shape)
