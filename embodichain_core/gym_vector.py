"""Gymnasium vector entry point for batched envs (kept import-light)."""

from __future__ import annotations

import importlib
from typing import Any


def make_vec_env(cls_path: str, num_envs: int = 1, **kwargs: Any) -> Any:
    """Build the env class at ``"module:Class"`` with ``num_envs``.

    The env is already batched, so it is its own vector env (``gym.make_vec(id,
    num_envs=N, vectorization_mode="vector_entry_point")``).
    """
    module, _, attr = cls_path.partition(":")
    cls = importlib.import_module(module)
    for part in attr.split("."):
        cls = getattr(cls, part)
    kwargs.pop("vectorization_mode", None)
    kwargs.pop("vector_kwargs", None)
    return cls(num_envs=num_envs, **kwargs)
