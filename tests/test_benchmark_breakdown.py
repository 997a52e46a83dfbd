"""``benchmarks/step_breakdown.py``: the instrumented pass splits an env step into the
MuJoCo calls, the task's functors and the framework's Python, and leaves the env as it
found it. No timing is asserted (the box is shared and noisy)."""

from __future__ import annotations

import pytest
from bench_testlib import import_benchmarks, run_benchmark, run_script


@pytest.fixture(scope="module")
def bench():
    return import_benchmarks("env_throughput", "step_breakdown")


@pytest.fixture
def env(bench):
    et, _ = bench
    env = et.make_env(2)
    yield env
    env.close()


def _functor_entries(base):
    return {
        (m, name): entry.func
        for m in ("event_manager", "observation_manager", "reward_manager")
        for name, entry in getattr(base, m).entries.items()
    }


def test_functor_timer_counts_functors_and_their_entity_calls_only(bench, env):
    et, sb = bench
    base = env.unwrapped
    actions = et.make_actions(env)
    with sb.FunctorTimer(base) as timer:
        base.scene["cube0"].get_local_pose()  # the framework's (or a user's) own call: not a functor's
        assert timer.functors == timer.entity == 0.0
        for i in range(12):  # the push fires on step 10 of an episode; observations and rewards every step
            env.step(actions[i])
        assert timer.functors > timer.entity > 0.0
        timer.reset_counts()
        assert timer.functors == timer.entity == 0.0


def test_functor_timer_restores_the_env(bench, env):
    _, sb = bench
    base = env.unwrapped
    before = _functor_entries(base)
    with sb.FunctorTimer(base):
        assert all(base.scene["cube0"].__dict__.get(n) is not None for n in ("get_local_pose", "set_velocity"))
        assert all(isinstance(f, sb._TimedFunctor) for f in _functor_entries(base).values())
    assert _functor_entries(base) == before
    for ent in base.scene.entities.values():
        assert not [n for n in vars(ent) if n.startswith(("get_", "set_"))], ent


def test_timed_functor_passes_attributes_through(bench):
    _, sb = bench

    class Counter:
        def __init__(self):
            self.resets = []

        def __call__(self, env, env_ids):
            return len(env_ids)

        def reset(self, env_ids):
            self.resets.append(env_ids)

    func = Counter()
    timer = sb.FunctorTimer(env=None)  # the env is read only on entering the context
    timed = sb._TimedFunctor(func, timer)
    assert timed(None, [1, 2]) == 2
    timed.reset([0])  # a class functor keeps its reset(env_ids)
    assert func.resets == [[0]]
    assert timer.depth == 0
    assert timer.functors > 0.0


def test_breakdown_reports_the_split_and_the_ceiling(bench, env):
    et, sb = bench
    base = env.unwrapped
    actions = et.make_actions(env)
    run_env = et.cycling(env.step, actions)
    raw_runs = []
    parts = sb.breakdown(base, run_env, lambda n: raw_runs.append(n), steps=4, repeats=2)
    assert raw_runs == [4, 4]  # a raw run after each env run
    assert parts["repeats"] == 2
    assert parts["functors_ms"] >= parts["functor_entity_ms"] > 0.0
    assert parts["task_functor_ms"] == pytest.approx(parts["functors_ms"] - parts["functor_entity_ms"])
    assert parts["framework_python_ms"] < parts["env_python_ms"]
    raw, env_ms = parts["raw_ms_per_call"], parts["env_ms_per_call"]
    assert parts["ceiling_ratio"] == pytest.approx(raw / (env_ms - parts["framework_python_ms"]))
    assert base.sim.__dict__["batch"].__class__.__name__ == "Batch"  # the batch is back


def test_verdicts_name_a_target_above_the_ceiling(bench):
    et, _ = bench
    lines = et._step_overhead_verdicts(
        [
            {"num_envs": 16, "ratio": 0.78, "ratio_matched": 0.86, "breakdown": {"ceiling_ratio": 0.85}},
            {"num_envs": 64, "ratio": 0.85, "ratio_matched": 0.92, "breakdown": {"ceiling_ratio": 0.88}},
        ]
    )
    assert lines == [
        "num_envs=16: target >= 0.8: ratio 0.780 MISSES, ratio_matched 0.860 meets, ceiling 0.850",
        "num_envs=64: target >= 0.9: ratio 0.850 MISSES, ratio_matched 0.920 meets, ceiling 0.880 (below the target)",
    ]


def test_breakdown_is_none_without_a_batch(bench):
    _, sb = bench

    class NoBatch:
        sim = type("Sim", (), {})()

    assert sb.breakdown(NoBatch(), lambda n: None, lambda n: None, steps=1, repeats=1) is None


@pytest.mark.timeout(300)
def test_cold_ops_quick_run_writes_json(tmp_path):
    _, data = run_benchmark("cold_ops.py", "--num-envs", "2", "--rounds", "3", out=tmp_path / "cold.json")
    records = data["records"]
    assert [r["between"] for r in records] == ["nothing", "batch", "sleep", "spin"]
    for rec in records:
        assert rec["num_envs"] == 2
        assert all(rec[k] > 0 for k in ("torch.zeros", "numpy arith", "repeat of all", "first touch / warm"))
    assert records[0]["first touch / warm"] == 1.0  # the warm probe is its own yardstick
    assert records[1]["between_ms"] == records[2]["between_ms"] > 0  # sleep and spin last as long as the step


def test_cold_ops_rejects_bad_arguments():
    proc = run_script("cold_ops.py", "--rounds", "0", timeout=120)
    assert proc.returncode == 2
    assert "must be positive" in proc.stderr
