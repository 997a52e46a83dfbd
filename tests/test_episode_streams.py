"""Per-episode random streams: an env's episode is a function of (seed, env index,
episode index) alone: another env's divergence, extra resets or a different
``num_envs`` never change it; explicit episode seeds replay an episode on any slot."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch
from core_testlib import base_cfg

from embodichain_core.envs.episode_rng import STARTUP_EPISODE, EpisodeRandom, derive_seed
from embodichain_core.managers import EventCfg, ObservationCfg, SceneEntityCfg

CUBE = SceneEntityCfg(uid="cube")


def jitter_cube(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, xy_range: tuple) -> None:
    """Moves the cube by a draw from each env's episode stream."""
    obj = env.scene[entity_cfg.uid]
    ids = torch.arange(env.num_envs) if env_ids is None else torch.as_tensor(env_ids).long()
    pose = obj.get_local_pose()[ids].clone()
    pose[:, :2] += torch.from_numpy(env.rng.uniform(ids, xy_range[0], xy_range[1])).to(pose.dtype)
    obj.set_local_pose(pose, ids)


def cube_pose(env: Any, obs: Any, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    return env.scene[entity_cfg.uid].get_local_pose().float()


def stream_cfg(num_envs: int, seed: int = 11) -> Any:
    params = {"entity_cfg": CUBE, "xy_range": ((-0.1, -0.1), (0.1, 0.1))}
    return base_cfg(
        num_envs=num_envs,
        seed=seed,
        max_episode_steps=4,
        events={
            "jitter": EventCfg(func=jitter_cube, mode="reset", params=params),
            "nudge": EventCfg(
                func=jitter_cube,
                mode="interval",
                interval_step=3,
                params={"entity_cfg": CUBE, "xy_range": ((-0.01, -0.01), (0.01, 0.01))},
            ),
        },
        observations={
            "cube": ObservationCfg(func=cube_pose, mode="add", name="object/cube_pose", params={"entity_cfg": CUBE})
        },
    )


def env0_trace(make_env: Any, num_envs: int, diverge_at: int | None = None, steps: int = 14) -> list[torch.Tensor]:
    """Env 0's cube pose and arm qpos at every step (actions of env 0 depend on the step alone)."""
    env = make_env(stream_cfg(num_envs))
    obs, _ = env.reset()
    trace = [obs["object"]["cube_pose"][0].clone()]
    for t in range(steps):
        if diverge_at is not None and t == diverge_at:
            env.sim.qvel[1, 0] = float("nan")
        action = torch.full((num_envs, 7), 0.05 * ((t % 5) - 2))
        with pytest.warns(RuntimeWarning) if diverge_at == t else _no_warning():
            obs, *_ = env.step(action)
        trace.append(torch.cat([obs["object"]["cube_pose"][0], obs["robot"]["qpos"][0]]).clone())
    return trace


class _no_warning:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: Any) -> None:
        return None


def test_env0_is_bit_identical_whatever_env1_does_and_num_envs(make_env, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo appends divergence warnings to ./MUJOCO_LOG.TXT
    clean = env0_trace(make_env, 2)
    diverged = env0_trace(make_env, 2, diverge_at=2)
    wider = env0_trace(make_env, 3, diverge_at=5)
    assert len(clean) == len(diverged) == len(wider) == 15
    for t, (a, b, c) in enumerate(zip(clean, diverged, wider)):
        assert torch.equal(a, b), f"step {t}: env 1's divergence changed env 0"
        assert torch.equal(a, c), f"step {t}: num_envs=3 changed env 0"
    # the episodes did differ from one another (3 resets of env 0 within 14 steps)
    starts = [clean[0][:2]] + [clean[t][:2] for t in (4, 8, 12)]
    assert len({tuple(s.tolist()) for s in starts}) == 4


def test_episode_seeds_follow_the_documented_rule(make_env) -> None:
    env = make_env(stream_cfg(3, seed=5))
    env.reset()
    assert env.episode_seeds.tolist() == derive_seed(5, np.arange(3), 0).tolist()
    env.reset(options={"reset_ids": [1]})
    assert env.episode_seeds[1] == derive_seed(5, 1, 1)
    assert env.episode_seeds[0] == derive_seed(5, 0, 0)  # untouched
    env.reset(seed=5)  # reseeding restarts every env at its episode 0
    assert env.episode_seeds.tolist() == derive_seed(5, np.arange(3), 0).tolist()


def test_an_episode_replays_on_another_slot_from_its_seed(make_env) -> None:
    env = make_env(stream_cfg(3, seed=5))
    obs, _ = env.reset()
    seed_of_env2 = int(env.episode_seeds[2])
    start_of_env2 = obs["object"]["cube_pose"][2].clone()
    obs, _ = env.reset(options={"reset_ids": [0], "episode_seeds": [seed_of_env2]})
    assert int(env.episode_seeds[0]) == seed_of_env2
    assert torch.equal(obs["object"]["cube_pose"][0], start_of_env2)


@pytest.mark.parametrize(
    "seeds, match",
    [
        ([1, 2], "2 value"),
        ([-1], r"ints in \[0, 2\*\*64\)"),
        (["a"], r"ints in \[0, 2\*\*64\)"),
        ([2**64], r"ints in \[0, 2\*\*64\)"),
    ],
)
def test_bad_episode_seeds_option_is_a_clear_error(make_env, seeds: list, match: str) -> None:
    env = make_env(stream_cfg(2))
    with pytest.raises(ValueError, match=match) as err:
        env.reset(options={"reset_ids": [0], "episode_seeds": seeds})
    assert "episode_seeds" in str(err.value)


def test_streams_are_independent_of_the_other_ids_drawn_with() -> None:
    a, b = EpisodeRandom(4, seed=1), EpisodeRandom(4, seed=1)
    a.begin_episodes(None)
    b.begin_episodes(None)
    together = a.random([0, 1, 2, 3], (5,))
    alone = np.concatenate([b.random([i], (5,)) for i in (3, 1, 0, 2)])
    assert np.array_equal(together[[3, 1, 0, 2]], alone)
    # a draw of m values advances the stream by m: two draws of 2 equal one draw of 4
    a.begin_episodes([0], seeds=[99])
    b.begin_episodes([0], seeds=[99])
    assert np.array_equal(np.concatenate([a.random([0], (2,)), a.random([0], (2,))], axis=1), b.random([0], (4,)))


def test_startup_streams_differ_from_episode_streams() -> None:
    rng = EpisodeRandom(2, seed=3)
    assert rng.episode_seeds.tolist() == derive_seed(3, np.arange(2), np.uint64(STARTUP_EPISODE)).tolist()
    startup = rng.random(None, (3,))
    rng.begin_episodes(None)
    assert not np.array_equal(startup, rng.random(None, (3,)))


def test_draw_distributions() -> None:
    rng = EpisodeRandom(2, seed=0)
    u = rng.random(None, (50_000,))
    assert u.min() >= 0.0
    assert u.max() < 1.0
    assert abs(u.mean() - 0.5) < 0.01
    assert abs(np.corrcoef(u[0], u[1])[0, 1]) < 0.02  # the two envs' streams are uncorrelated
    k = rng.integers([0], 6, (60_000,))
    assert set(np.unique(k).tolist()) == set(range(6))
    assert np.abs(np.bincount(k.ravel()) / k.size - 1 / 6).max() < 0.01
    z = rng.normal([1], (40_000,))
    assert abs(z.mean()) < 0.03
    assert abs(z.std() - 1.0) < 0.03
    lo_hi = rng.uniform([0, 1], [-2.0, 10.0], [-1.0, 20.0])
    assert lo_hi.shape == (2, 2)
    assert ((lo_hi >= [-2.0, 10.0]) & (lo_hi < [-1.0, 20.0])).all()


def test_seed_range_is_checked() -> None:
    with pytest.raises(ValueError, match="seed"):
        EpisodeRandom(2, seed=-3)
    with pytest.raises(ValueError, match="seed"):
        derive_seed(2**64, 0)
    with pytest.raises(ValueError, match=">= 1"):
        EpisodeRandom(1, seed=0).integers(None, 0)
