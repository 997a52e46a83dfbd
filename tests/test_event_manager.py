"""EventManager through the env loop: startup, reset, interval (per env and global),
custom modes, and class functors' ``reset(env_ids)``."""

from __future__ import annotations

from typing import Any

import pytest
import torch

from core_testlib import call_log, ids_list, zero_action

from embodichain_core.managers import EventCfg, Functor, SceneEntityCfg


def log_event(env: Any, env_ids: Any, tag: str) -> None:
    """Records ``(tag, env_ids as list or None, the env_ids object)``."""
    call_log(env).append((tag, ids_list(env_ids), env_ids))


def tags(env: Any, tag: str) -> list:
    return [ids for t, ids, _ in call_log(env) if t == tag]


def run_steps(env: Any, n: int, tag: str, on_step: Any = None) -> dict[int, list]:
    """Step ``n`` times; return {step number: [env ids lists fired during that step]}."""
    fired: dict[int, list] = {}
    for k in range(1, n + 1):
        before = len(call_log(env))
        env.step(zero_action(env))
        new = [ids for t, ids, _ in call_log(env)[before:] if t == tag]
        if new:
            fired[k] = new
        if on_step is not None:
            on_step(k)
    return fired


def test_startup_runs_once_with_none(make_env) -> None:
    env = make_env(events={"boot": EventCfg(func=log_event, mode="startup", params={"tag": "startup"})})
    assert [(t, ids) for t, ids, _ in call_log(env)] == [("startup", None)]
    env.reset()
    run_steps(env, 3, "startup")
    env.reset(options={"reset_ids": [1]})
    assert tags(env, "startup") == [None]


def test_reset_events_get_only_the_reset_ids(make_env, make_cfg) -> None:
    from core_testlib import FlagEnv

    env = make_env(
        make_cfg(num_envs=3, events={"r": EventCfg(func=log_event, mode="reset", params={"tag": "reset"})}),
        env_cls=FlagEnv,
    )
    assert tags(env, "reset") == []  # construction runs startup events only
    env.reset()
    assert tags(env, "reset") == [[0, 1, 2]]
    env.reset(options={"reset_ids": [2]})
    assert tags(env, "reset")[-1] == [2]
    env.success_flags[1] = True  # env 1 ends and is auto-reset in the same step
    env.step(zero_action(env))
    assert tags(env, "reset")[-1] == [1]
    assert len(tags(env, "reset")) == 3


def test_interval_counters_are_per_env_and_restart_on_partial_reset(make_env) -> None:
    env = make_env(events={"tick": EventCfg(func=log_event, mode="interval", interval_step=5, params={"tag": "tick"})})
    env.reset()

    def reset_env1_at_3(k: int) -> None:
        if k == 3:
            env.reset(options={"reset_ids": [1]})

    fired = run_steps(env, 10, "tick", on_step=reset_env1_at_3)
    assert fired == {5: [[0]], 8: [[1]], 10: [[0]]}


def test_interval_counters_restart_on_auto_reset(make_env) -> None:
    env = make_env(
        max_episode_steps=4,
        events={"tick": EventCfg(func=log_event, mode="interval", interval_step=3, params={"tag": "tick"})},
    )
    env.reset()
    fired = run_steps(env, 12, "tick")
    # step 3 of each 4-step episode: global steps 3, 7, 11 (never 6, 9, 12)
    assert fired == {3: [[0, 1]], 7: [[0, 1]], 11: [[0, 1]]}


def test_interval_schedule_matches_per_env_counters_under_random_resets(make_env) -> None:
    """The cached phases fire exactly the envs a plain per-env counter would, and a
    functor that mutates its env_ids cannot change later schedules."""

    def mutating(env: Any, env_ids: Any, tag: str) -> None:
        log_event(env, env_ids, tag)
        env_ids.fill_(0)

    env = make_env(
        num_envs=5,
        events={"tick": EventCfg(func=mutating, mode="interval", interval_step=3, params={"tag": "tick"})},
    )
    env.reset()
    counters = [0] * 5
    rng = torch.Generator().manual_seed(3)
    for k in range(1, 41):
        before = len(call_log(env))
        env.step(zero_action(env))
        counters = [c + 1 for c in counters]
        expected = [i for i, c in enumerate(counters) if c % 3 == 0]
        fired = [ids for t, ids, _ in call_log(env)[before:] if t == "tick"]
        assert fired == ([expected] if expected else []), f"step {k}"
        resets = torch.nonzero(torch.rand(5, generator=rng) < 0.25).flatten().tolist()
        if resets:
            env.reset(options={"reset_ids": resets})
            for i in resets:
                counters[i] = 0
        assert env.event_manager.interval_counters("tick").tolist() == counters
    with pytest.raises(KeyError, match=r"'tock' is not an interval event; interval events: \['tick'\]"):
        env.event_manager.interval_counters("tock")


def test_global_interval_fires_all_envs_together(make_env) -> None:
    env = make_env(
        num_envs=3,
        events={
            "glob": EventCfg(func=log_event, mode="interval", interval_step=3, is_global=True, params={"tag": "g"}),
        },
    )
    env.reset()
    fired = run_steps(env, 10, "g")
    assert fired == {3: [None], 6: [None], 9: [None]}


def test_global_interval_ignores_partial_resets(make_env) -> None:
    env = make_env(
        events={
            "glob": EventCfg(func=log_event, mode="interval", interval_step=3, is_global=True, params={"tag": "g"}),
        }
    )
    env.reset()
    fired = run_steps(env, 6, "g", on_step=lambda k: k == 2 and env.reset(options={"reset_ids": [0]}))
    assert sorted(fired) == [3, 6]


def test_interval_rejects_env_ids_and_bad_step(make_env, make_cfg) -> None:
    from embodichain_core.config.errors import ConfigError

    env = make_env(events={"tick": EventCfg(func=log_event, mode="interval", interval_step=2, params={"tag": "t"})})
    with pytest.raises(ValueError):
        env.event_manager.apply("interval", torch.tensor([0]))
    with pytest.raises(ConfigError, match=r"env\.events\.tick\.interval_step"):
        make_env(events={"tick": EventCfg(func=log_event, mode="interval", interval_step=0, params={"tag": "t"})})


def test_custom_mode_runs_only_when_applied(make_env) -> None:
    env = make_env(
        events={"attach": EventCfg(func=log_event, mode="attach", params={"tag": "attach"})},
        custom_event_modes=["attach"],
    )
    env.reset()
    run_steps(env, 3, "attach")
    env.reset(options={"reset_ids": [0]})
    assert tags(env, "attach") == []
    ids = torch.tensor([1])
    env.event_manager.apply("attach", ids)
    calls = [c for c in call_log(env) if c[0] == "attach"]
    assert len(calls) == 1
    assert calls[0][2] is ids
    assert "attach" in env.event_manager.available_modes


def test_event_moves_only_selected_envs(make_env) -> None:
    def lift(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, dz: float) -> None:
        obj = env.scene[entity_cfg.uid]
        pose = obj.get_local_pose()[env_ids].clone()
        pose[:, 2] += dz
        obj.set_local_pose(pose, env_ids)

    env = make_env(
        num_envs=3,
        custom_event_modes=["custom"],
        events={
            "lift": EventCfg(func=lift, mode="custom", params={"entity_cfg": SceneEntityCfg(uid="cube"), "dz": 0.5}),
        },
    )
    env.reset()
    before = env.scene["cube"].get_local_pose().clone()
    env.event_manager.apply("custom", torch.tensor([0, 2]))
    after = env.scene["cube"].get_local_pose()
    assert torch.allclose(after[[0, 2], 2], before[[0, 2], 2] + 0.5)
    assert torch.equal(after[1], before[1])


class CountingEvent(Functor):
    """A class event functor recording its calls and resets."""

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.calls: list = []
        self.resets: list = []

    def __call__(self, env: Any, env_ids: Any, gain: float = 1.0) -> None:
        self.calls.append(ids_list(env_ids))

    def reset(self, env_ids: Any = None) -> None:
        self.resets.append(ids_list(env_ids))


def test_class_event_functor_reset_gets_the_reset_ids(make_env) -> None:
    env = make_env(
        num_envs=3,
        events={
            "count": EventCfg(func=CountingEvent, mode="interval", interval_step=1, params={"gain": 2.0}),
        },
    )
    functor = env.event_manager.get_functor("count")
    assert isinstance(functor, CountingEvent)
    assert functor.cfg.params["gain"] == 2.0
    env.reset()
    assert functor.resets == [[0, 1, 2]]
    env.step(zero_action(env))
    assert functor.calls == [[0, 1, 2]]
    env.reset(options={"reset_ids": [1, 2]})
    assert functor.resets[-1] == [1, 2]


def test_event_cfg_is_copied_per_manager(make_env, make_cfg) -> None:
    cfg = make_cfg(events={"count": EventCfg(func=CountingEvent, mode="reset")})
    a, b = make_env(cfg), make_env(cfg)
    a.reset()
    assert a.event_manager.get_functor("count") is not b.event_manager.get_functor("count")
    assert b.event_manager.get_functor("count").calls == []
    assert cfg.events["count"].func is CountingEvent  # the user's config is left untouched


def test_each_functor_is_resolved_once_per_build(make_env, monkeypatch) -> None:
    """Validation resolves every functor; the filter, the scene hooks and the managers
    build from that result instead of resolving again."""
    import embodichain_core.managers.manager_base as manager_base

    calls: list[str] = []
    resolve = manager_base.resolve_functor

    def counting(func: Any, kind: str, path: str) -> Any:
        calls.append(path)
        return resolve(func, kind, path)

    monkeypatch.setattr(manager_base, "resolve_functor", counting)
    events = {
        "boot": EventCfg(func=log_event, mode="startup", params={"tag": "s"}),
        "tick": EventCfg(func=f"{__name__}:log_event", mode="reset", params={"tag": "r"}),
    }
    make_env(events=events, filter_visual_rand=True)
    assert sorted(calls) == ["env.events.boot", "env.events.tick"]
