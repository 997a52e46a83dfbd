"""Class-functor bases: ``Functor``, ``ActionTerm`` and ``DatasetFunctor``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional

import torch


class Functor:
    """A stateful functor, built once with ``(cfg, env)``.

    Subclasses implement ``__call__`` with the manager's call convention (events:
    ``(env, env_ids, **params)``) and may override :meth:`reset`, which the managers
    call with the env ids being reset.

    A class may also define ``modify_scene(cls, cfg, scene)`` (a classmethod): it
    runs before the scene is compiled, to add what the functor needs (textures,
    mesh variants).
    """

    def __init__(self, cfg: Any, env: Any):
        self.cfg = cfg
        self._env = env

    @property
    def num_envs(self) -> int:
        return self._env.num_envs

    @property
    def device(self) -> torch.device:
        return self._env.device

    if TYPE_CHECKING:  # an instance's name is a str (mypy would read the property as a method)
        __name__: str
    else:

        @property
        def __name__(self) -> str:
            return type(self).__name__

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        """Clear per-env state of ``env_ids`` (all when ``None``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        raise NotImplementedError(f"{type(self).__name__} must implement __call__")


class ActionTerm(Functor):
    """Turns (part of) the policy action into robot commands.

    Attributes:
        input_key: which command it produces: ``qpos``, ``qvel``, ``qf`` or ``eef_pose``.
    """

    input_key: str = "qpos"

    @property
    def action_dim(self) -> int:
        """Size of this term's slice of the policy action."""
        return len(self._env.active_joint_ids)

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        """(low, high) of this term's policy action (defaults to unbounded)."""
        inf = torch.full((self.action_dim,), float("inf"))
        return -inf, inf

    def process_action(self, action: torch.Tensor) -> Any:
        """Map the (N, action_dim) policy action to a command."""
        raise NotImplementedError(f"{type(self).__name__} must implement process_action")

    def action_names(self) -> list[str]:
        """A name per value of this term's action (the recorded ``action`` columns): the
        active joints' names when it takes one value per active joint, else ``<class>.<i>``."""
        joints = list(self._env.active_joint_ids)
        if self.action_dim == len(joints):
            return [str(self._env.robot.joint_names[j]) for j in joints]
        return [f"{type(self).__name__}.{i}" for i in range(self.action_dim)]

    def action_from_qpos(self, qpos: torch.Tensor) -> torch.Tensor:
        """The (N, action_dim) action that commands the (N, n_active) joint position targets
        ``qpos``: how a scripted demonstration written as joint targets drives, and is
        recorded in, this action space. A term that cannot express a joint target (one
        relative to the current state, a velocity or an effort) raises NotImplementedError.
        """
        raise NotImplementedError(f"{type(self).__name__} cannot express joint position targets as its action")

    def __call__(self, action: torch.Tensor) -> Any:
        return self.process_action(action)


class DatasetFunctor(Functor):
    """A recorder driven by the dataset manager.

    ``record_step`` runs after every env step; ``__call__(env, env_ids, **params)``
    commits the finished episodes of ``env_ids``; ``discard(env_ids)`` drops their
    buffered frames; ``finalize()`` closes the dataset (never committing partial
    episodes) and returns where the data went. A recorder that reads
    ``env.rollout_buffer`` instead of buffering frames itself sets
    ``uses_rollout_buffer = True``.
    """

    uses_rollout_buffer: bool = False

    def record_step(
        self, obs: Any, action: Any, reward: torch.Tensor, terminated: torch.Tensor, truncated: torch.Tensor, info: dict
    ) -> None:
        """Buffer one frame per env."""

    def record_reset(self, obs: Any, env_ids: torch.Tensor) -> None:
        """Observe the first observation of new episodes of ``env_ids``."""

    def discard(self, env_ids: torch.Tensor) -> None:
        """Drop the buffered frames of ``env_ids``."""

    def finalize(self) -> Optional[str]:
        """Flush and close; return the dataset path."""
        return None
