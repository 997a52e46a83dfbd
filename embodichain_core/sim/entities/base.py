"""Common plumbing of scene entities: env-id handling and name lookup."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any, Sequence

import mujoco
import numpy as np
import torch

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


class Entity:
    """Base of every scene entity: ``uid``, ``cfg``, the scene and its batch."""

    kind = "entity"

    def __init__(self, uid: str, cfg: Any, scene: "Scene"):
        self.uid = uid
        self.cfg = cfg
        self.scene = scene

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

    def _host_reads(self) -> bool:
        """Whether reads may use the simulation's numpy views (a CPU backend with host
        arrays and CPU outputs): ~1 us per slice where the torch op costs ~3-5 us."""
        host = self.__dict__.get("_host_reads_ok")
        if host is None:
            sim = self.sim
            host = (
                bool(getattr(getattr(sim, "capabilities", None), "host_arrays", False))
                and getattr(sim, "device", torch.device("cpu")).type == "cpu"
                and self.device.type == "cpu"
            )
            self.__dict__["_host_reads_ok"] = host
        return host

    @staticmethod
    def _pose_out(pos: np.ndarray, quat: np.ndarray) -> torch.Tensor:
        """A fresh float32 ``(n, 7)`` pose tensor from ``(n, 3)`` positions and ``(n, 4)`` quaternions."""
        out = np.empty((len(pos), 7), dtype=np.float32)
        out[:, :3] = pos
        out[:, 3:] = quat
        return torch.from_numpy(out)

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
