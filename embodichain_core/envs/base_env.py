"""``BaseEnv``: the name the batched env base had before the loop moved into
:class:`~embodichain_core.envs.embodied_env.EmbodiedEnv` (its only subclass). Kept as
an alias so ``issubclass(cls, BaseEnv)`` and older imports keep working."""

from __future__ import annotations

from embodichain_core.envs.embodied_env import EmbodiedEnv

BaseEnv = EmbodiedEnv

__all__ = ["BaseEnv"]
