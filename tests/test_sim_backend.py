"""The simulation interface: ``BatchSim`` passes the conformance checks any backend runs,
and a functor's subset step reports divergence through the env loop."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch

from core_testlib import zero_action

from embodichain_core.sim.backend import BatchSim, SimBackend
from embodichain_core.sim.backend import conformance
from embodichain_core.sim.backend.env_rows import batch_ids


def make_batch_sim(model: Any, num_envs: int) -> BatchSim:
    return BatchSim(model, num_envs, substeps=2)


@pytest.mark.parametrize("check", conformance.CHECKS, ids=lambda c: c.__name__)
def test_batch_sim_conforms(check: Any) -> None:
    check(make_batch_sim)


def test_a_backend_that_swallows_divergence_fails_the_checks() -> None:
    class Swallowing(BatchSim):
        def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
            super().step(nstep, env_ids)
            return []

    with pytest.raises(AssertionError, match="did not report"):
        conformance.check_divergence(lambda model, n: Swallowing(model, n))


def test_a_backend_whose_subset_step_moves_every_env_fails_the_checks() -> None:
    class AllEnvs(BatchSim):
        def step(self, nstep: int = 1, env_ids: Any = None) -> list[int]:
            return super().step(nstep)

    with pytest.raises(AssertionError, match="a subset step changed other envs"):
        conformance.check_step(lambda model, n: AllEnvs(model, n))


def test_env_sim_is_the_interface(make_env) -> None:
    env = make_env()
    assert isinstance(env.sim, SimBackend)
    assert env.sim.capabilities.subset_step


def test_subset_step_of_a_functor_reports_divergence_at_the_next_env_step(make_env) -> None:
    from embodichain_functors._sim import step_envs

    env = make_env(num_envs=3)
    env.reset()
    cube = env.scene["cube"]
    env.sim.qvel[1, cube.dof_adr] = float("nan")
    env.sim.mark_dirty([1])
    assert step_envs(env, torch.tensor([0, 1]), 2) == [1]
    with pytest.warns(RuntimeWarning, match=r"diverged in env\(s\) \[1\]"):
        _, _, _, truncated, info = env.step(zero_action(env))
    assert info["diverged"].tolist() == [False, True, False]
    assert truncated.tolist() == [False, True, False]
    assert torch.isfinite(env.sim.qpos).all()  # the autoreset cleared it


def test_only_the_backend_touches_mujoco_batch() -> None:
    """The core and the plugins' packages reach the simulation through the interface only."""
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    backend = root / "embodichain_core" / "sim" / "backend"
    pattern = re.compile(
        r"import mujoco\.batch|mujoco import batch|mujoco\.batch\.|\bsim\.batch\b|\._expanded\b|\.set_models\("
    )
    sources = list((root / "embodichain_core").rglob("*.py"))
    for plugin in (root / "plugins").iterdir():
        sources += [p for p in plugin.rglob("*.py") if "tests" not in p.relative_to(plugin).parts]
    offenders = [
        f"{p.relative_to(root)}:{n}"
        for p in sources
        if backend not in p.parents
        for n, line in enumerate(p.read_text().splitlines(), 1)
        if pattern.search(line)
    ]
    assert not offenders, f"outside sim/backend/: {offenders}"


def test_batch_ids_are_sorted_unique_int32_or_none_for_every_env() -> None:
    assert batch_ids(None, 3) is None
    assert batch_ids(torch.tensor([0, 1, 2]), 3) is None
    assert batch_ids([2, 0, 1], 3) is None  # unsorted, still every env
    for ids, want in (([1], [1]), ([2, 0], [0, 2]), ([1, 1, 0], [0, 1]), ([0, 0, 2], [0, 2]), ([], [])):
        got = batch_ids(ids, 3)
        assert got is not None, ids
        assert got.dtype == np.int32, ids
        assert got.tolist() == want, ids
    got = batch_ids([0, 5], 2)  # as many ids as envs, but not every env: left for mujoco.batch to reject
    assert got is not None
    assert got.tolist() == [0, 5]


def test_a_non_finite_control_or_position_reports_the_env(make_env) -> None:
    """MuJoCo ignores a non-finite control (it warns and steps on); the scan after the step
    still reports the env, as it does a non-finite position."""
    env = make_env(num_envs=3)
    env.reset()
    sim = env.sim
    sim.arrays["ctrl"][1, 0] = float("nan")
    assert sim.step(1) == [1]
    sim.reset([1])
    sim.arrays["qpos"][2, 0] = float("inf")
    sim.mark_dirty([2])
    assert sim.step(1) == [2]
    assert sim.step(1) == [2]  # still non-finite: reported until the env is reset
