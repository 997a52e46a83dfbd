"""Flatten embodichain's nested, batched observation dicts into what RL libraries take.

An embodichain observation is a nested dict of ``(num_envs, ...)`` tensors, for example
``{"robot": {"qpos", "qvel", "qf"}, "cube_pose", "goal_position", "sensor": {"cam": {"color"}}}``.
Neither rsl_rl (2-D observation groups) nor Stable-Baselines3 (no nested ``Dict`` spaces)
accepts it as is. :class:`ObsFlattener` fixes one layout from the env's single-env
observation space:

* every leaf gets its path, the keys joined with ``"/"`` (``"robot/qpos"``);
* leaves are taken in **sorted path order** (``cube_pose``, ``eef_position``,
  ``goal_position``, ``robot/qf``, ``robot/qpos``, ``robot/qvel`` for ``PushCube-v1``), so
  the layout depends on the set of keys only, not on dict insertion order;
* **image** leaves (``uint8`` boxes with 3 dims, ``(H, W, C)``) are kept apart, one entry each;
* every other leaf is cast to float32, reshaped to ``(num_envs, -1)`` and concatenated into
  one ``state`` vector of :attr:`state_dim` values.

``ObsFlattener.from_dict(flattener.to_dict())`` restores a layout (checkpoints store it), and
leaves the layout does not name (a camera added for a video) are ignored.

Example:
    >>> flat = ObsFlattener.from_space(env.single_observation_space)  # doctest: +SKIP
    >>> flat.state(obs).shape  # doctest: +SKIP
    torch.Size([8, 34])
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
import torch

__all__ = ["ObsFlattener", "leaf"]


def leaf(obs: Any, path: str) -> Any:
    """The value at ``path`` (keys joined with ``"/"``) of a nested observation dict."""
    node = obs
    for key in path.split("/"):
        if not isinstance(node, dict) or key not in node:
            raise KeyError(f"observation has no entry {path!r} (missing {key!r})")
        node = node[key]
    return node


def _walk(space: gym.Space, prefix: str = "") -> list[tuple[str, gym.spaces.Box]]:
    if isinstance(space, gym.spaces.Dict):
        out: list[tuple[str, gym.spaces.Box]] = []
        for key in space.spaces:
            out += _walk(space.spaces[key], f"{prefix}{key}/")
        return out
    if not isinstance(space, gym.spaces.Box):
        raise TypeError(
            f"observation {prefix.rstrip('/')!r}: only Box and Dict spaces can be flattened, got {type(space).__name__}"
        )
    return [(prefix.rstrip("/"), space)]


def _is_image(space: gym.spaces.Box) -> bool:
    return space.dtype == np.uint8 and len(space.shape) == 3


@dataclass
class ObsFlattener:
    """A fixed layout: ``state`` leaves (concatenated) and ``image`` leaves (kept apart).

    Attributes:
        state_paths: paths of the state leaves, sorted.
        state_sizes: number of values of each state leaf (one env).
        image_paths: paths of the image leaves, sorted.
        image_shapes: ``(H, W, C)`` of each image leaf.
    """

    state_paths: list[str]
    state_sizes: list[int]
    image_paths: list[str] = field(default_factory=list)
    image_shapes: list[tuple[int, ...]] = field(default_factory=list)

    @classmethod
    def from_space(cls, single_space: gym.Space, skip: tuple[str, ...] = ()) -> "ObsFlattener":
        """The layout of a **single-env** observation space; paths starting with an entry
        of ``skip`` (``"sensor"``: every camera) are left out."""
        leaves = sorted((p, s) for p, s in _walk(single_space) if not p.startswith(skip))
        state = [(p, int(np.prod(s.shape))) for p, s in leaves if not _is_image(s)]
        images = [(p, tuple(int(d) for d in s.shape)) for p, s in leaves if _is_image(s)]
        if not state and not images:
            raise ValueError("the observation has no leaves to flatten")
        return cls([p for p, _ in state], [n for _, n in state], [p for p, _ in images], [s for _, s in images])

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "ObsFlattener":
        """Rebuild a layout written by :meth:`to_dict`."""
        return cls(
            list(data["state_paths"]),
            [int(n) for n in data["state_sizes"]],
            list(data.get("image_paths", [])),
            [tuple(s) for s in data.get("image_shapes", [])],
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-friendly copy of the layout."""
        return {
            "state_paths": list(self.state_paths),
            "state_sizes": list(self.state_sizes),
            "image_paths": list(self.image_paths),
            "image_shapes": [list(s) for s in self.image_shapes],
        }

    @property
    def state_dim(self) -> int:
        """Length of the state vector of one env."""
        return int(sum(self.state_sizes))

    def state(self, obs: Any) -> torch.Tensor:
        """The ``(num_envs, state_dim)`` float32 state vector of a batched observation."""
        parts = []
        for path, size in zip(self.state_paths, self.state_sizes):
            value = torch.as_tensor(leaf(obs, path)).to(torch.float32)
            value = value.reshape(value.shape[0], -1)
            if value.shape[1] != size:
                raise ValueError(f"observation {path!r} has {value.shape[1]} values per env, the layout expects {size}")
            parts.append(value)
        if not parts:
            return torch.zeros(0, 0)
        return torch.cat(parts, dim=-1)

    def images(self, obs: Any) -> dict[str, torch.Tensor]:
        """``{path: (num_envs, H, W, C) uint8}`` of the image leaves."""
        return {path: torch.as_tensor(leaf(obs, path)) for path in self.image_paths}

    def state_space(self) -> gym.spaces.Box:
        """The single-env Box of the state vector (unbounded float32)."""
        return gym.spaces.Box(-np.inf, np.inf, (self.state_dim,), np.float32)
