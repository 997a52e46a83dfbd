"""Helpers of the functors: ranges are checked and cached, model writes run mj_setConst
once and touch only the envs written (the rotations are the core's, tests/test_math.py)."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import field

from embodichain_core.envs.episode_rng import EpisodeRandom

from embodichain_functors._common import ParamError, as_range, uniform
from embodichain_functors._sim import write_model


def test_ranges_are_checked_and_cached() -> None:
    rng = [[0.0, 1.0], [2.0, 3.0]]
    low, high = as_range(rng, "f", "p", 2)
    assert as_range(rng, "f", "p", 2)[0] is low  # converted once per param object
    assert torch.equal(as_range([[1.0], [2.0]], "f", "p", 3)[1], torch.full((3,), 2.0, dtype=torch.float64))
    for bad in ([1.0], [[0, 0], [1, 1, 1]], [2.0, 1.0], [0.0, float("nan")], "ab"):
        with pytest.raises(ParamError) as err:
            as_range(bad, "f", "p", 2 if isinstance(bad, list) and isinstance(bad[0], list) else None)
        assert err.value.path == "f.params.p"
        assert "functor 'f'" in err.value.reason


def test_uniform_draws_one_row_per_env_from_its_episode_stream() -> None:
    class Env:
        rng = EpisodeRandom(8, seed=0)

    Env.rng.begin_episodes(None)
    ids = torch.arange(8)
    draws = uniform(Env(), ids, torch.zeros(3), torch.ones(3))
    assert draws.shape == (8, 3)
    assert len(set(draws[:, 0].tolist())) == 8
    assert not torch.equal(uniform(Env(), ids, torch.zeros(3), torch.ones(3)), draws)  # the streams advanced
    Env.rng = EpisodeRandom(8, seed=0)
    Env.rng.begin_episodes(None)
    # env 5 alone draws what it drew as row 5 of the batch: rows never depend on the other ids
    assert torch.equal(uniform(Env(), torch.tensor([5]), torch.zeros(3), torch.ones(3))[0], draws[5])
    assert uniform(Env(), ids, torch.zeros(3), torch.ones(3), (2,)).shape == (8, 2, 3)


def test_write_model_defers_one_constants_update_for_the_written_envs(build, monkeypatch) -> None:
    from embodichain_core.sim.backend.free_body_const import FreeBodyConstants

    env = build()
    full, closed = [], []
    original = env.sim.batch.set_const
    env.sim.batch.set_const = lambda ids=None: (full.append(ids), original(ids))[1]
    update = FreeBodyConstants.update
    monkeypatch.setattr(
        FreeBodyConstants, "update", lambda self, ids, fields=None: (closed.append(ids), update(self, ids, fields))[1]
    )
    body = env.scene["cube"].body_id
    before = field(env, "body_mass")[:, body]
    write_model(
        env.sim,
        torch.tensor([1, 2]),
        [
            ("body_mass", body, [2.0, 3.0]),
            ("body_inertia", body, 1e-3),
            ("geom_friction", (env.scene["cube"].geom_ids[0], 0), 0.9),
        ],
    )
    after = field(env, "body_mass")[:, body]
    assert after[1] == 2.0
    assert after[2] == 3.0
    assert after[0] == before[0]
    assert after[3] == before[3]
    assert full == closed == []  # deferred: one update before the sim is next used
    env.sim.flush_const()
    # the cube is a free body: its constants come in closed form
    assert full == []
    assert len(closed) == 1
    assert list(closed[0]) == [1, 2]
    write_model(env.sim, torch.tensor([0]), [("geom_friction", (env.scene["cube"].geom_ids[0], 0), 0.5)])
    env.sim.flush_const()
    assert len(full) + len(closed) == 1  # friction feeds no derived constant
    link = int(env.robot.body_ids[-1])
    write_model(env.sim, torch.tensor([3]), [("body_mass", link, 1.0), ("body_mass", body, 1.0)])
    env.sim.flush_const()
    assert len(full) == 1
    assert list(full[0]) == [3]
