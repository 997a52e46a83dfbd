"""The members of :class:`~embodichain_core.envs.base_env.BaseEnv` and ``EmbodiedEnv`` that
tasks and functors use besides the loop: sizes and timing, the task override points
(``compute_task_state``, ``get_reward``, ``check_truncated``, ``is_task_success``,
``get_info``, ``evaluate``), and small extras (affordances, detached entities, sensors).

``step`` calls the override points at fixed phases (see the env module); a task
subclass overrides them and never the loop itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch


class TaskApi:
    """Mixin of :class:`BaseEnv` (which sets ``_num_envs``, ``step_dt``, ``physics_dt``,
    ``_elapsed_steps``, ``rng``, ``scene``, ``sensors`` and ``affordance_datas``)."""

    _num_envs: int
    step_dt: float
    physics_dt: float
    _elapsed_steps: torch.Tensor
    rng: Any
    scene: Any
    sensors: dict[str, Any]
    affordance_datas: dict[str, Any]
    _detached_uids_for_reset: list[str]

    # -- sizes and timing ----------------------------------------------------------------------
    @property
    def num_envs(self) -> int:
        return self._num_envs

    @property
    def control_frequency(self) -> float:
        return 1.0 / self.step_dt

    @property
    def physics_frequency(self) -> float:
        return 1.0 / self.physics_dt

    @property
    def elapsed_steps(self) -> torch.Tensor:
        """Each env's step counter (live; 0 right after its reset)."""
        return self._elapsed_steps

    @property
    def episode_seeds(self) -> np.ndarray:
        """Each env's current episode seed (uint64, ``(num_envs,)``): the key of its
        random stream (``env.rng``), recorded with the episode for exact replay."""
        return self.rng.episode_seeds

    @property
    def unwrapped(self) -> Any:
        return self

    @property
    def sim(self) -> Any:
        """The simulation backend (:class:`~embodichain_core.sim.backend.SimBackend`)."""
        return self.scene.sim

    # -- task override points ----------------------------------------------------------------------
    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        """``(success, fail, metrics)``, (N,) bool each (none by default)."""
        return torch.zeros(self.num_envs, dtype=torch.bool), torch.zeros(self.num_envs, dtype=torch.bool), {}

    def get_info(self, **kwargs: Any) -> dict:
        """``success``, ``fail``, ``elapsed_steps`` (a copy of the counters) and ``metrics``."""
        success, fail, metrics = self.compute_task_state(**kwargs)
        elapsed = self._elapsed_steps.clone()  # a copy: the counters move on
        return {"success": success, "fail": fail, "elapsed_steps": elapsed, "metrics": metrics}

    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        """Task reward before reward functors (zeros by default)."""
        return torch.zeros(self.num_envs)

    def check_truncated(self, obs: Any, info: dict) -> torch.Tensor:
        """Task-specific truncation (none by default)."""
        return torch.zeros(self.num_envs, dtype=torch.bool)

    def is_task_success(self, **kwargs: Any) -> torch.Tensor:
        """Whether each env's current state counts as a success (for dataset saving)."""
        return self.compute_task_state(**kwargs)[0]

    def evaluate(self, **kwargs: Any) -> dict:
        """Per-env ``success`` plus metrics (every env, not only env 0)."""
        info = self.get_info(**kwargs)
        return {"success": info["success"], "fail": info["fail"], **info["metrics"]}

    # -- extras ----------------------------------------------------------------------------------
    def add_detached_uids_for_reset(self, uids: Any) -> None:
        """Exclude entities from the automatic reset to their initial state."""
        self._detached_uids_for_reset += [uids] if isinstance(uids, str) else list(uids)

    def get_sensor(self, name: str) -> Any:
        return self.scene[name]

    @property
    def has_sensors(self) -> bool:
        return bool(self.sensors)

    def set_affordance(self, key: str, value: Any) -> None:
        self.affordance_datas[key] = value

    def get_affordance(self, key: str, default: Any = None) -> Any:
        return self.affordance_datas.get(key, default)
