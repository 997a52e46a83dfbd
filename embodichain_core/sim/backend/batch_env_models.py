"""Per-env models of a :class:`~embodichain_core.sim.backend.batch_sim.BatchSim`: envs that need
different model structures (``Batch.set_models``), each with its own ``MjModel`` copy."""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any, Iterable, Optional, Sequence

import mujoco

from embodichain_core.sim.backend.env_rows import np_ids as _np_ids


class PerEnvModels:
    """Mixin of :class:`BatchSim` (which provides ``model``, ``batch``, ``num_envs``,
    ``forward``, ``flush_const``, ``mark_dirty`` and ``_make_batch``)."""

    model: mujoco.MjModel
    batch: Any  # the mujoco.batch.Batch
    num_envs: int
    env_models: Optional[list[mujoco.MjModel]]

    if TYPE_CHECKING:  # defined by BatchSim (and BatchConstants)

        def forward(self, env_ids: Any = None) -> None: ...

        def flush_const(self) -> None: ...

        def mark_dirty(self, env_ids: Any = None) -> None: ...

        def _make_batch(self) -> None: ...

    def _set_const_models(self, ids: Iterable[int]) -> None:
        """``mj_setConst`` on the per-env models of ``ids`` (their current state as the data)."""
        if self.env_models is None:
            raise RuntimeError("_set_const_models needs per-env models (use_env_models first)")
        data = mujoco.MjData(self.model)
        for env in ids:
            model = self.env_models[env]
            self.batch.get_data(int(env), data)
            mujoco.mj_setConst(model, data)

    def use_env_models(self, models: Sequence[mujoco.MjModel]) -> None:
        """Run env ``i`` on ``models[i]`` (same data layout), keeping every env's state.

        Expanded fields are folded into the new models first, so values written
        before the switch are kept.
        """
        if len(models) != self.num_envs:
            raise ValueError(f"need one model per env ({self.num_envs}), got {len(models)}")
        self.flush_const()
        state = self.batch.state.copy()
        expanded = {name: self.batch.expanded(name) for name in list(self.batch._expanded)}
        models = [copy.copy(m) for m in models]
        for name, values in expanded.items():
            if values is None or name.startswith("opt."):
                continue
            for env, model in enumerate(models):
                if getattr(model, name).shape == values[env].shape:
                    getattr(model, name)[...] = values[env]
        self._make_batch()
        self.batch.state[...] = state
        self.batch.set_models(models)
        self.env_models = models
        self.forward(None)

    def set_env_model(self, env_ids: Any, model: mujoco.MjModel) -> None:
        """Give ``env_ids`` a copy of ``model`` (e.g. a structural variant)."""
        if self.env_models is None:
            self.use_env_models([self.batch.get_model(i) for i in range(self.num_envs)])
        env_models = self.env_models
        assert env_models is not None  # set by use_env_models
        for env in _np_ids(env_ids, self.num_envs):
            env_models[env] = copy.copy(model)
        self.batch.set_models(env_models)
        self.mark_dirty(env_ids)
