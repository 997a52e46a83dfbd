"""Env-id and element-index normalization shared by the batched simulation."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import torch


def np_ids(env_ids: Any, n: int) -> np.ndarray:
    """``env_ids`` (None, slice, list, array, tensor, bool mask) as an int64 array of rows
    (no copy for an int64 array or a CPU long tensor)."""
    if isinstance(env_ids, np.ndarray) and env_ids.dtype == np.int64 and env_ids.ndim == 1:
        return env_ids
    if isinstance(env_ids, torch.Tensor):
        if env_ids.dtype == torch.long and env_ids.device.type == "cpu" and env_ids.dim() == 1:
            return env_ids.numpy()  # the common case: ids from env_index
        env_ids = env_ids.detach().cpu().numpy()
    elif env_ids is None or (isinstance(env_ids, slice) and env_ids == slice(None)):
        return np.arange(n)
    arr = np.asarray(env_ids)
    if arr.dtype == bool:
        return np.flatnonzero(arr)
    return np.atleast_1d(arr).astype(np.int64)


def index_bodies(index: Any) -> Optional[list[int]]:
    """Body ids a model-field index selects (``None`` when it cannot tell)."""
    if isinstance(index, tuple):
        return index_bodies(index[0]) if index else None
    if isinstance(index, (int, np.integer)):
        return [int(index)]
    if isinstance(index, (list, np.ndarray, torch.Tensor)):
        return [int(i) for i in np.asarray(index).reshape(-1)]
    return None


def batch_ids(env_ids: Any, n: int) -> Optional[np.ndarray]:
    """Sorted unique int32 ids as ``mujoco.batch`` takes them; ``None`` for every env."""
    if env_ids is None:
        return None
    ids = np_ids(env_ids, n)
    if ids.size > 1 and not (ids[1:] > ids[:-1]).all():  # np.unique only when not sorted unique already
        ids = np.unique(ids)
    if len(ids) == n and ids[0] == 0 and ids[-1] == n - 1:
        return None
    return ids.astype(np.int32)


def _is_list(index: Any) -> bool:
    return isinstance(index, (list, np.ndarray, torch.Tensor))


def field_selector(ids: np.ndarray, index: Any) -> tuple:
    """``field[selector]`` of model-field ``index`` for env rows ``ids``.

    A list index (or a tuple whose first element is a list) selects several elements:
    the result then has shape ``(n, k, ...)``.
    """
    if isinstance(index, (int, np.integer)):
        return ids, index
    if _is_list(index):
        return ids[:, None], np.asarray(index, dtype=np.int64).reshape(-1)[None, :]
    if isinstance(index, tuple) and index and _is_list(index[0]):
        return (ids[:, None], np.asarray(index[0], dtype=np.int64).reshape(-1)[None, :]) + index[1:]
    if isinstance(index, tuple):
        return (ids,) + index
    return ids, index
