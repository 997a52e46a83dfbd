"""Gymnasium spaces from observations (nested dicts of batched tensors)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import torch


def space_from_obs(obs: Any, batched: bool = True) -> gym.Space:
    """Per-env space of a batched observation: dicts become ``Dict``, tensors ``Box``.

    Floats get +-inf bounds; integers and bools their dtype's bounds.
    """
    if isinstance(obs, dict):
        return gym.spaces.Dict({k: space_from_obs(v, batched) for k, v in obs.items()})
    arr = obs.detach().cpu().numpy() if isinstance(obs, torch.Tensor) else np.asarray(obs)
    shape = arr.shape[1:] if batched else arr.shape
    dtype = arr.dtype
    if dtype == np.bool_:
        return gym.spaces.Box(low=0, high=1, shape=shape, dtype=np.bool_)
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        return gym.spaces.Box(low=info.min, high=info.max, shape=shape, dtype=dtype)
    return gym.spaces.Box(low=-np.inf, high=np.inf, shape=shape, dtype=dtype)


def batch_space(space: gym.Space, n: int) -> gym.Space:
    """The batched space (leading ``n``)."""
    return gym.vector.utils.batch_space(space, n)
