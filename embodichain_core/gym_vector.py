"""Gymnasium vector entry point for batched envs, and an unbatched single-env wrapper
for gymnasium's own vector envs (kept import-light: gymnasium, numpy and torch are
imported when used).

An embodichain env is already batched, so ``gym.make_vec(task_id, num_envs=N)`` builds one
env with ``num_envs=N`` (:func:`make_vec_env`, the ``"vector_entry_point"`` mode, the
default). gymnasium's ``"sync"`` and ``"async"`` modes instead stack N single envs. Tasks
are registered with a :class:`BatchedEnvSpec`, so those single envs are
:class:`UnbatchedEnv` s (gymnasium's single-env layout), and every mode gives rewards and
flags of shape ``(N,)``; ``gym.make(task_id)`` still builds the batched env (a batch of
one). ``"async"`` needs the ``"spawn"`` start method (MuJoCo's threads do not survive a
``fork``):

Example (``task_id``: any registered task, ``embodichain list tasks``):
    >>> venv = gym.make_vec(task_id, num_envs=4, vectorization_mode="async",
    ...                     vector_kwargs={"context": "spawn"})  # doctest: +SKIP
    >>> _, reward, *_ = venv.step(venv.action_space.sample())  # doctest: +SKIP
    >>> reward.shape  # doctest: +SKIP
    (4,)
"""

from __future__ import annotations

import copy
import dataclasses
import importlib
from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import EnvSpec

__all__ = ["make_vec_env", "UnbatchedEnv", "BatchedEnvSpec", "SingleEnvEntryPoint", "batched_spec"]


def make_vec_env(cls_path: str | type, num_envs: int = 1, **kwargs: Any) -> Any:
    """Build the env class at ``"module:Class"`` (or the class itself) with ``num_envs``.

    The env is already batched, so it is its own vector env (``gym.make_vec(id,
    num_envs=N, vectorization_mode="vector_entry_point")``).
    """
    cls: Any = cls_path
    if isinstance(cls_path, str):
        module, _, attr = cls_path.partition(":")
        cls = importlib.import_module(module)
        for part in attr.split("."):
            cls = getattr(cls, part)
    kwargs.pop("vectorization_mode", None)
    kwargs.pop("vector_kwargs", None)
    return cls(num_envs=num_envs, **kwargs)


def _row(value: Any) -> Any:
    """Row 0 of a batched value as numpy, a Python scalar for ``(N,)`` values (dicts
    recursively); other values unchanged."""
    import numpy as np
    import torch

    if isinstance(value, dict):
        return {k: _row(v) for k, v in value.items()}
    if isinstance(value, torch.Tensor):
        value = value.detach().cpu().numpy()
    if isinstance(value, np.ndarray) and value.ndim:
        row = value[0]
        return row.item() if row.ndim == 0 else row
    return value


class UnbatchedEnv(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """A ``num_envs=1`` embodichain env in gymnasium's single-env layout (numpy).

    Observations, info values and spaces lose the batch dim; ``reward`` is a float and
    ``terminated``/``truncated`` are bools; actions are ``(action_dim,)`` arrays. When an
    episode ends the env has already reset itself (same-step autoreset): the observation
    returned is the episode's last one (``info["final_obs"]``), and the caller (a gymnasium
    vector env) resets as after any single env's episode.

    Wrapping an ``UnbatchedEnv`` again changes nothing (``make_vec(..., wrappers=[UnbatchedEnv])``
    of a task whose sub-envs are already unbatched). The wrapper records itself in the env's
    ``spec`` (gymnasium's ``RecordConstructorArgs``), so ``env.spec.make()`` rebuilds the wrapped
    env, as gymnasium's ``check_env`` does.

    Args:
        env: the env, built with ``num_envs=1`` (``gym.make(task_id)``).
    """

    def __init__(self, env: gym.Env):
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        self._passthrough = isinstance(env, UnbatchedEnv)
        if self._passthrough:
            self.observation_space, self.action_space = env.observation_space, env.action_space
            self.metadata = env.metadata
            return
        batched: Any = env.unwrapped
        if int(getattr(batched, "num_envs", 1)) != 1:
            raise ValueError(f"UnbatchedEnv needs num_envs=1, got {batched.num_envs}")
        self.observation_space = batched.single_observation_space
        self.action_space = batched.single_action_space
        self.metadata = {**env.metadata, "autoreset_mode": None}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        """Reset; the observation and info without the batch dim."""
        if self._passthrough:
            return self.env.reset(seed=seed, options=options)
        obs, info = self.env.reset(seed=seed, options=options)
        return _row(obs), _row(info)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Step with an ``(action_dim,)`` action (a batch of one is applied as is)."""
        import numpy as np
        import torch

        if self._passthrough:
            obs, reward, terminated, truncated, info = self.env.step(action)
            return obs, float(reward), terminated, truncated, info
        batch = torch.as_tensor(np.asarray(action, dtype=np.float32)).reshape(1, -1)
        out: Any = self.env.step(batch)
        obs, reward, info = out[0], out[1], out[4]
        terminated, truncated = bool(out[2][0]), bool(out[3][0])
        if (terminated or truncated) and "final_obs" in info:
            obs, info = info["final_obs"], info.get("final_info", info)
        return _row(obs), float(reward[0]), terminated, truncated, _row(info)


class SingleEnvEntryPoint:
    """gymnasium entry point of one sub-env of a ``"sync"``/``"async"`` vector env: the
    task's batched env with ``num_envs=1``, wrapped in :class:`UnbatchedEnv`.

    Args:
        entry_point: the task's own entry point (``"module:Class"`` or a callable).
    """

    def __init__(self, entry_point: Any):
        self.entry_point = entry_point

    def __call__(self, **kwargs: Any) -> gym.Env:
        """Build the sub-env with the ``gym.make`` kwargs."""
        from gymnasium.envs.registration import load_env_creator

        entry = self.entry_point
        creator = entry if callable(entry) else load_env_creator(entry)
        env = creator(**kwargs)
        if not isinstance(env, gym.Env):  # a vector env creator, or a class that is no gymnasium.Env
            raise TypeError(f"entry point {entry!r} built a {type(env).__name__}, not a gymnasium.Env")
        return UnbatchedEnv(env)

    def __repr__(self) -> str:
        return f"SingleEnvEntryPoint({self.entry_point!r})"


class BatchedEnvSpec(EnvSpec):
    """The gymnasium spec of a batched task.

    ``gym.make(spec)`` builds the batched env as any spec does. ``gym.make_vec`` works on a
    deep copy of the registered spec; the copy this class makes is a plain ``EnvSpec``
    whose entry point is a :class:`SingleEnvEntryPoint`, so the sub-envs of gymnasium's
    ``"sync"`` and ``"async"`` vector envs are unbatched single envs, and the vector env
    returns ``(N,)`` rewards and flags. The ``"vector_entry_point"`` mode is unchanged.
    """

    def __deepcopy__(self, memo: dict) -> EnvSpec:
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(EnvSpec) if f.init}
        values = {
            k: v if k in ("entry_point", "vector_entry_point") else copy.deepcopy(v, memo) for k, v in values.items()
        }
        values["entry_point"] = SingleEnvEntryPoint(self.entry_point)
        return EnvSpec(**values)


def batched_spec(spec: EnvSpec) -> BatchedEnvSpec:
    """``spec`` as a :class:`BatchedEnvSpec` (same fields; returned as is when it is one)."""
    if isinstance(spec, BatchedEnvSpec):
        return spec
    return BatchedEnvSpec(**{f.name: getattr(spec, f.name) for f in dataclasses.fields(EnvSpec) if f.init})
