"""Functors that pass a goal through an env attribute agree on its name: one default
(``goal_pose``), and a reader whose attribute no writer stores is a ConfigError."""

from __future__ import annotations

import inspect

import pytest
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg, ObservationCfg, RewardCfg
from embodichain_core.managers import SceneEntityCfg as E

import embodichain_functors.observations as obs
import embodichain_functors.randomization as rand
import embodichain_functors.rewards as rewards

GOAL = [[0.1, 0.2, 0.3], [0.1, 0.2, 0.3]]


def goal_event(**params) -> dict:
    return {"goal": EventCfg(func=rand.randomize_target_pose, mode="reset", params={"position_range": GOAL, **params})}


def goal_obs(**params) -> dict:
    return {"goal_obs": ObservationCfg(func=obs.target_position, mode="add", name="task/goal", params=params)}


def test_the_writer_and_every_reader_default_to_the_same_key() -> None:
    def default(func, name: str) -> str:
        target = func.__call__ if inspect.isclass(func) else func
        return inspect.signature(target).parameters[name].default

    assert default(rand.randomize_target_pose, "store_key") == "goal_pose"
    for reader in (
        obs.target_position,
        rewards.distance_to_target,
        rewards.incremental_distance_to_target,
        rewards.reaching_behind_object,
    ):
        assert default(reader, "target_pose_key") == "goal_pose", reader


def test_defaults_alone_give_the_goal_to_the_observation(build) -> None:
    env = build(observations=goal_obs(), events=goal_event())
    o, _ = env.reset()
    assert torch.allclose(o["task"]["goal"], torch.tensor(GOAL[0]).expand(4, 3))


def test_an_observation_reading_a_key_no_writer_stores_is_an_error_naming_both(build) -> None:
    with pytest.raises(ConfigError) as err:
        build(observations=goal_obs(), events=goal_event(store_key="target_pose"))
    assert err.value.path == "env.observations.goal_obs.params.target_pose_key"
    reason = err.value.reason
    assert "target_position reads env.goal_pose" in reason
    assert "randomize_target_pose (env.events.goal) stores env.target_pose (params.store_key)" in reason


def test_a_reward_reading_a_key_no_writer_stores_is_an_error(build) -> None:
    reward = RewardCfg(
        func=rewards.distance_to_target,
        weight=1.0,
        params={"source_entity_cfg": E(uid="cube"), "target_pose_key": "goal"},
    )
    with pytest.raises(ConfigError) as err:
        build(rewards={"near": reward}, events=goal_event())
    assert err.value.path == "env.rewards.near.params.target_pose_key"
    assert "distance_to_target reads env.goal" in err.value.reason
    assert "randomize_target_pose" in err.value.reason


def test_without_a_writer_the_key_must_exist_after_the_first_reset(build) -> None:
    env = build(observations=goal_obs())  # task code could still set env.goal_pose
    with pytest.raises(ConfigError) as err:
        env.reset()
    assert err.value.path == "env.observations.goal_obs.params.target_pose_key"
    assert "does not exist after the first reset" in err.value.reason
    fine = build(observations=goal_obs())
    fine.goal_pose = torch.ones(4, 3)  # set by the task
    o, _ = fine.reset()
    assert torch.equal(o["task"]["goal"], torch.ones(4, 3))
