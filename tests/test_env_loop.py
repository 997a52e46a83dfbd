"""The env loop: same-step auto-reset, per-env truncation, partial resets,
determinism, timing, extensions, num_envs, gymnasium registration, divergence,
and the config filters."""

from __future__ import annotations

import math
import uuid
import warnings
from typing import Any

import gymnasium as gym
import pytest
import torch
from gymnasium.vector import AutoresetMode

from core_testlib import CUBE_INIT, FlagEnv, base_cfg, zero_action

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs import BaseEnv, EmbodiedEnv, EmbodiedEnvCfg, register_env
from embodichain_core.managers import EventCfg, ObservationCfg, SceneEntityCfg
from embodichain_core.sim.cfg import SimulationManagerCfg


def cube_pose(env: Any, obs: dict, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    return env.scene[entity_cfg.uid].get_local_pose()


CUBE_OBS = {
    "cube": ObservationCfg(
        func=cube_pose, mode="add", name="object/cube_pose", params={"entity_cfg": SceneEntityCfg(uid="cube")}
    )
}


def leaves(obs: Any, prefix: str = "") -> dict[str, torch.Tensor]:
    if isinstance(obs, dict):
        out: dict[str, torch.Tensor] = {}
        for k, v in obs.items():
            out.update(leaves(v, f"{prefix}/{k}"))
        return out
    return {prefix: obs}


# -- auto-reset and termination ------------------------------------------------------------------
def test_same_step_autoreset_keeps_the_final_observation(make_env, make_cfg) -> None:
    env = make_env(make_cfg(observations=CUBE_OBS), env_cls=FlagEnv)
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    env.reset()
    target = torch.full((2, 7), 0.3)
    for _ in range(3):
        obs, *_ = env.step(target)
    moved = obs["robot"]["qpos"].clone()
    assert moved[0, 0] > 0.1
    env.success_flags[0] = True
    obs, reward, terminated, truncated, info = env.step(target)
    assert terminated.tolist() == [True, False]
    assert truncated.tolist() == [False, False]
    assert info["_final_obs"].tolist() == [True, False]
    final = info["final_obs"]
    assert final["robot"]["qpos"][0, 0] > 0.1  # the terminal state, not the reset one
    assert torch.all(obs["robot"]["qpos"][0] == 0)  # env 0 starts over
    assert torch.equal(obs["robot"]["qpos"][1], final["robot"]["qpos"][1])  # env 1 untouched
    assert torch.allclose(obs["object"]["cube_pose"][0, :3], torch.tensor(CUBE_INIT))
    assert env.elapsed_steps.tolist() == [0, 4]
    assert info["elapsed_steps"].tolist() == [4, 4]  # this step counted, as the task state saw it
    assert info["final_info"]["success"].tolist() == [True, False]
    env.success_flags[0] = False
    _, _, terminated, _, info = env.step(target)
    assert terminated.tolist() == [False, False]
    assert "final_obs" not in info


def test_truncation_is_per_env(make_env) -> None:
    env = make_env(max_episode_steps=5)
    env.reset()
    history = []
    for k in range(1, 8):
        _, _, terminated, truncated, _ = env.step(zero_action(env))
        history.append(truncated.tolist())
        assert not terminated.any()
        if k == 2:
            env.reset(options={"reset_ids": [1]})
    assert history[4] == [True, False]  # env 0 at step 5
    assert history[6] == [False, True]  # env 1 five steps after its reset
    assert sum(map(sum, history)) == 2
    assert env.elapsed_steps.tolist() == [2, 0]


def test_every_step_returns_its_own_tensors(make_env) -> None:
    """A caller may keep (and write) what a step returned: the next step neither reuses
    those tensors nor their memory, and writing them changes neither the env nor the next step."""
    env = make_env(max_episode_steps=50)
    env.reset()
    first = env.step(zero_action(env))
    kept = leaves({"obs": first[0], "reward": first[1], "terminated": first[2], "truncated": first[3]})
    kept.update(leaves({k: v for k, v in first[4].items() if isinstance(v, torch.Tensor)}, "/info"))
    before = {k: v.clone() for k, v in kept.items()}
    for value in kept.values():  # the caller scribbles over everything it kept
        value.fill_(1)
    second = env.step(zero_action(env))
    fresh = leaves({"obs": second[0], "reward": second[1], "terminated": second[2], "truncated": second[3]})
    fresh.update(leaves({k: v for k, v in second[4].items() if isinstance(v, torch.Tensor)}, "/info"))
    assert set(fresh) == set(kept)
    pointers = {v.data_ptr() for v in kept.values()}
    for key, value in fresh.items():
        assert value is not kept[key], key
        assert value.data_ptr() not in pointers, key
    assert env.elapsed_steps.tolist() == [2, 2]  # the counters were not written through the info copy
    assert fresh["/info/elapsed_steps"].tolist() == [2, 2]
    for key in ("/terminated", "/truncated", "/info/success", "/info/fail", "/info/diverged"):
        assert not fresh[key].any(), key
    assert torch.equal(fresh["/reward"], before["/reward"])


def test_ignore_terminations(make_env, make_cfg) -> None:
    env = make_env(make_cfg(ignore_terminations=True, max_episode_steps=3), env_cls=FlagEnv)
    env.reset()
    env.success_flags[:] = True
    env.fail_flags[1] = True
    for k in range(1, 4):
        _, _, terminated, truncated, info = env.step(zero_action(env))
        assert not terminated.any()
        assert info["success"].all()
        assert truncated.tolist() == ([True, True] if k == 3 else [False, False])
    assert env.elapsed_steps.tolist() == [0, 0]


def test_partial_reset_touches_only_those_envs(make_env) -> None:
    env = make_env(num_envs=3)
    env.reset()
    cube = env.scene["cube"]
    pose = cube.get_local_pose().clone()
    pose[:, 0] += torch.tensor([0.1, 0.2, 0.3])
    cube.set_local_pose(pose)
    for _ in range(3):
        env.step(torch.full((3, 7), 0.2))
    cube_before = cube.get_local_pose().clone()
    qpos_before = env.robot.get_qpos().clone()
    steps_before = env.elapsed_steps.clone()
    obs, _ = env.reset(options={"reset_ids": [1]})
    after = cube.get_local_pose()
    assert torch.equal(after[[0, 2]], cube_before[[0, 2]])
    assert torch.allclose(after[1, :3], torch.tensor(CUBE_INIT))
    assert torch.equal(env.robot.get_qpos()[[0, 2]], qpos_before[[0, 2]])
    assert torch.all(env.robot.get_qpos()[1] == 0)
    assert env.elapsed_steps.tolist() == [int(steps_before[0]), 0, int(steps_before[2])]
    assert obs["robot"]["qpos"].shape == (3, 7)  # every row is returned


# -- determinism ------------------------------------------------------------------------------------
def jitter_cube(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, xy_range: tuple) -> None:
    obj = env.scene[entity_cfg.uid]
    ids = torch.as_tensor(env_ids).long()
    pose = obj.get_local_pose()[ids].clone()
    low, high = torch.tensor(xy_range[0]), torch.tensor(xy_range[1])
    pose[:, :2] += low + (high - low) * torch.rand(len(ids), 2, generator=env.generator)
    obj.set_local_pose(pose, ids)


def seeded_cfg(seed: int) -> EmbodiedEnvCfg:
    return base_cfg(
        num_envs=3,
        seed=seed,
        observations=CUBE_OBS,
        events={
            "jitter": EventCfg(
                func=jitter_cube,
                mode="reset",
                params={"entity_cfg": SceneEntityCfg(uid="cube"), "xy_range": ((-0.1, -0.1), (0.1, 0.1))},
            ),
        },
    )


def rollout(env: Any, steps: int = 20) -> list[dict[str, torch.Tensor]]:
    actions = torch.Generator().manual_seed(123)
    low = torch.as_tensor(env.action_space.low)
    high = torch.as_tensor(env.action_space.high)
    obs, _ = env.reset()
    out = [leaves(obs)]
    for _ in range(steps):
        action = low + (high - low) * torch.rand(low.shape, generator=actions)
        obs, reward, *_ = env.step(action * 0.5)
        out.append({**leaves(obs), "reward": reward})
    return out


def test_same_seed_gives_bit_identical_rollouts(make_env) -> None:
    a = rollout(make_env(seeded_cfg(7)))
    b = rollout(make_env(seeded_cfg(7)))
    assert len(a) == 21
    for frame_a, frame_b in zip(a, b):
        assert frame_a.keys() == frame_b.keys()
        for key in frame_a:
            assert torch.equal(frame_a[key], frame_b[key]), key
    moved = a[-1]["/robot/qpos"] - a[0]["/robot/qpos"]
    assert moved.abs().max() > 0.05  # the actions did something


def test_different_seed_differs_and_reset_seed_reseeds(make_env) -> None:
    env_a, env_b = make_env(seeded_cfg(7)), make_env(seeded_cfg(8))
    pose_a = env_a.reset()[0]["object"]["cube_pose"]
    pose_b = env_b.reset()[0]["object"]["cube_pose"]
    assert not torch.equal(pose_a, pose_b)
    assert not torch.equal(pose_a[0], pose_a[1])  # envs are randomized independently
    pose_a = env_a.reset(seed=42)[0]["object"]["cube_pose"]
    pose_b = env_b.reset(seed=42)[0]["object"]["cube_pose"]
    assert torch.equal(pose_a, pose_b)
    assert env_a.cfg.seed == 42


def test_no_seed_draws_one_and_records_it(make_env) -> None:
    env, other = make_env(seeded_cfg(None)), make_env(seeded_cfg(None))
    seed = env.cfg.seed
    assert isinstance(seed, int)
    assert 0 <= seed < 2**31
    assert other.cfg.seed != seed  # drawn per env (equal with probability 2**-31)
    # the recorded seed repeats the run: same episode streams, same randomized first observation
    replay = make_env(seeded_cfg(seed))
    first, again = env.reset()[0], replay.reset()[0]
    assert env.episode_seeds.tolist() == replay.episode_seeds.tolist()
    assert torch.equal(first["object"]["cube_pose"], again["object"]["cube_pose"])


# -- timing ---------------------------------------------------------------------------------------
def test_timing_is_exact(make_env, make_cfg) -> None:
    env = make_env(make_cfg(sim_cfg=SimulationManagerCfg(physics_dt=0.006), sim_steps_per_control=7))
    assert env.physics_dt == 0.006
    assert env.sim_steps_per_control == 7
    assert env.step_dt == pytest.approx(0.042, abs=1e-12)
    assert env.physics_frequency == pytest.approx(1 / 0.006)
    assert env.control_frequency == pytest.approx(1 / 0.042)
    assert env.metadata["render_fps"] == env.control_frequency
    assert "render_fps" not in BaseEnv.metadata
    assert "render_fps" not in EmbodiedEnv.metadata
    env.reset()
    t0 = env.sim.batch.bind("time").copy()
    env.step(zero_action(env))
    dt = env.sim.batch.bind("time") - t0
    assert dt.tolist() == pytest.approx([0.042, 0.042], abs=1e-9)  # one env.step = 7 physics steps


def test_target_control_frequency(make_env, make_cfg) -> None:
    env = make_env(make_cfg(target_control_frequency=20, sim_steps_per_control=2))
    assert env.sim_steps_per_control == 5
    assert env.step_dt == pytest.approx(0.05)
    assert env.cfg.sim_steps_per_control == 5
    with pytest.raises(ConfigError, match="cannot be represented exactly"):
        make_env(make_cfg(target_control_frequency=30))


@pytest.mark.parametrize(
    "field,value",
    [
        ("physics_dt", 0.0),
        ("physics_dt", -0.01),
        ("physics_dt", math.nan),
        ("physics_dt", math.inf),
        ("sim_steps_per_control", 0),
        ("sim_steps_per_control", True),
        ("sim_steps_per_control", 1.5),
        ("target_control_frequency", 0.0),
        ("target_control_frequency", -20.0),
        ("target_control_frequency", math.inf),
    ],
)
def test_invalid_timing_raises(make_env, make_cfg, field: str, value: Any) -> None:
    cfg = make_cfg()
    if field == "physics_dt":
        cfg.sim_cfg.physics_dt = value
    else:
        setattr(cfg, field, value)
    with pytest.raises(ConfigError, match=field):
        make_env(cfg)


# -- construction ----------------------------------------------------------------------------------------
def test_extensions_are_bound_onto_the_env(make_env) -> None:
    env = make_env(extensions={"success_threshold": 0.1, "goal_names": ["a", "b"]})
    assert env.success_threshold == 0.1
    assert env.goal_names == ["a", "b"]
    with pytest.raises(ConfigError, match=r"env\.extensions\.step"):
        make_env(extensions={"step": 1})


def test_num_envs_from_sim_cfg(make_env, make_cfg) -> None:
    env = make_env(make_cfg(num_envs=1, sim_cfg=SimulationManagerCfg(num_envs=3)))
    assert env.num_envs == 3
    assert env.cfg.num_envs == 3
    obs, _ = env.reset()
    assert obs["robot"]["qpos"].shape == (3, 7)
    assert env.action_space.shape == (3, 7)
    with pytest.raises(ConfigError, match="num_envs"):
        make_env(make_cfg(num_envs=2, sim_cfg=SimulationManagerCfg(num_envs=3)))


def test_missing_robot_is_a_config_error(make_env) -> None:
    with pytest.raises(ConfigError, match="robot"):
        make_env(EmbodiedEnvCfg(verbose=False))


def test_evaluate_covers_every_env(make_env, make_cfg) -> None:
    env = make_env(make_cfg(num_envs=3), env_cls=FlagEnv)
    env.reset()
    env.success_flags[2] = True
    result = env.evaluate()
    assert result["success"].tolist() == [False, False, True]
    assert result["steps"].shape == (3,)


# -- gymnasium ------------------------------------------------------------------------------------------
class RegisteredEnv(EmbodiedEnv):
    """A module-level class so that gymnasium can import its entry point."""


@pytest.fixture
def registered_id() -> Any:
    uid = f"EcLoopTest{uuid.uuid4().hex[:8]}-v0"
    register_env(uid, max_episode_steps=4)(RegisteredEnv)
    yield uid
    gym.envs.registry.pop(uid, None)


def _wrappers(env: Any) -> list[type]:
    out = []
    while env is not None:
        out.append(type(env))
        env = getattr(env, "env", None)
    return out


def test_gym_make_without_time_limit(registered_id: str) -> None:
    default_limit = EmbodiedEnvCfg().max_episode_steps
    env = gym.make(registered_id, cfg=base_cfg(max_episode_steps=default_limit))
    try:
        assert gym.wrappers.TimeLimit not in _wrappers(env)
        assert isinstance(env.unwrapped, RegisteredEnv)
        assert env.unwrapped.max_episode_steps == 4
        env.reset()
        for k in range(1, 5):
            _, _, _, truncated, _ = env.step(zero_action(env.unwrapped))
            assert isinstance(truncated, torch.Tensor)
            assert truncated.shape == (2,)
            assert truncated.tolist() == ([True, True] if k == 4 else [False, False])
    finally:
        env.close()
    env = gym.make(registered_id, cfg=base_cfg(max_episode_steps=9))
    try:
        assert env.unwrapped.max_episode_steps == 9  # a config that sets its own limit keeps it
    finally:
        env.close()


def test_gym_make_vec_vector_entry_point(registered_id: str) -> None:
    venv = gym.make_vec(registered_id, num_envs=3, vectorization_mode="vector_entry_point", cfg=base_cfg())
    try:
        assert isinstance(venv.unwrapped, RegisteredEnv)
        assert venv.num_envs == 3
        obs, _ = venv.reset(seed=3)
        assert obs["robot"]["qpos"].shape == (3, 7)
        action = torch.linspace(-0.2, 0.2, 21).reshape(3, 7)
        obs, reward, terminated, truncated, _ = venv.step(action)
        assert reward.shape == terminated.shape == truncated.shape == (3,)
        # the vector env is the batched env itself: the same values as one built directly
        direct = RegisteredEnv(base_cfg(num_envs=3))
        direct.reset(seed=3)
        want_obs, want_reward, want_terminated, want_truncated, _ = direct.step(action)
        direct.close()
        assert torch.equal(obs["robot"]["qpos"], want_obs["robot"]["qpos"])
        assert torch.equal(reward, want_reward)
        assert torch.equal(terminated, want_terminated)
        assert torch.equal(truncated, want_truncated)
        assert not torch.equal(obs["robot"]["qpos"][0], obs["robot"]["qpos"][2])  # the rows are the envs'
    finally:
        venv.close()


def test_register_env_rejects_non_env_classes() -> None:
    with pytest.raises(TypeError):
        register_env(f"EcLoopBad{uuid.uuid4().hex[:8]}-v0")(object)


# -- divergence --------------------------------------------------------------------------------------------
def test_diverged_env_is_reset_with_a_warning(make_env, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo appends its warning to ./MUJOCO_LOG.TXT
    env = make_env(num_envs=3)
    env.reset()
    for _ in range(2):
        env.step(torch.full((3, 7), 0.2))
    env.sim.qvel[1, 0] = float("nan")
    with pytest.warns(RuntimeWarning, match=r"diverged.*\[1\]"):
        obs, _, _, truncated, info = env.step(torch.full((3, 7), 0.2))
    assert info["diverged"].tolist() == [False, True, False]
    assert truncated.tolist() == [False, True, False]
    assert env.elapsed_steps.tolist() == [3, 0, 3]
    assert all(torch.isfinite(v).all() for v in leaves(obs).values())
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        obs, *_ = env.step(torch.full((3, 7), 0.2))
    assert env.elapsed_steps.tolist() == [4, 1, 4]


# -- filters ------------------------------------------------------------------------------------------------
def randomize_cube_color(env: Any, env_ids: Any) -> None:
    env.__dict__.setdefault("visual_calls", []).append("randomize")


randomize_cube_color.embodichain_category = "randomization.visual"


def set_cube_color(env: Any, env_ids: Any) -> None:
    env.__dict__.setdefault("visual_calls", []).append("set")


set_cube_color.embodichain_category = "randomization.visual"


def randomize_cube_mass(env: Any, env_ids: Any) -> None:
    env.__dict__.setdefault("visual_calls", []).append("mass")


randomize_cube_mass.embodichain_category = "randomization.physics"

VISUAL_EVENTS = {
    "rand_color": EventCfg(func=randomize_cube_color, mode="reset"),
    "set_color": EventCfg(func=set_cube_color, mode="reset"),
    "rand_mass": EventCfg(func=randomize_cube_mass, mode="reset"),
}


def test_filter_visual_rand(make_env) -> None:
    env = make_env(events=VISUAL_EVENTS)
    assert set(env.event_manager.active_functors) == {"rand_color", "set_color", "rand_mass"}
    env = make_env(events=VISUAL_EVENTS, filter_visual_rand=True)
    assert set(env.event_manager.active_functors) == {"set_color", "rand_mass"}
    env.reset()
    assert env.visual_calls == ["set", "mass"]


def test_filter_visual_rand_with_registered_names(make_env) -> None:
    from embodichain_core.plugins import hookimpl, isolated_plugins, register_plugin

    class VisualPlugin:
        @hookimpl
        def embodichain_register_functors(self, register: Any) -> None:
            register("randomize_ec_loop_color", randomize_cube_color, kind="event", category="randomization.visual")
            register("set_ec_loop_color", set_cube_color, kind="event", category="randomization.visual")

    with isolated_plugins():
        register_plugin(VisualPlugin(), name="ec-loop-visual")
        events = {
            "rand": EventCfg(func="randomize_ec_loop_color", mode="reset"),
            "set": EventCfg(func="set_ec_loop_color", mode="reset"),
        }
        assert make_env(events=events).event_manager.active_functors == ["rand", "set"]
        assert make_env(events=events, filter_visual_rand=True).event_manager.active_functors == ["set"]


def test_active_joints_do_not_leak_between_envs(make_env) -> None:
    a = make_env()
    b = make_env(control_parts=None, active_joint_ids=[0, 2])
    assert a.active_joint_ids == list(range(7))
    assert b.active_joint_ids == [0, 2]
    assert b.action_space.shape == (2, 2)
    c = make_env()
    assert c.active_joint_ids == list(range(7))
    assert a.active_joint_ids == list(range(7))
    with pytest.raises(ConfigError, match="control_parts"):
        make_env(active_joint_ids=[0])  # together with control_parts


def test_rollout_buffer_holds_each_envs_episode_and_clears_on_reset(make_cfg):
    from embodichain_core.envs import EmbodiedEnv

    env = EmbodiedEnv(make_cfg(init_rollout_buffer=True, max_episode_steps=10), num_envs=2)
    obs0, _ = env.reset(seed=0)
    actions = [torch.full((2, 7), 0.1 * (k + 1)) for k in range(3)]
    for a in actions:
        env.step(a)
    buf = env.rollout_buffer
    assert buf.length.tolist() == [3, 3]
    ep = buf.episode(1)
    assert torch.allclose(ep["actions"], torch.stack([a[1] for a in actions]))
    assert torch.equal(ep["obs/robot/qpos"][0], obs0["robot"]["qpos"][1])  # frame 0 = the obs acted on
    env.reset(options={"reset_ids": [0]})
    assert buf.length.tolist() == [0, 3]


def randomize_cube_tint(env: Any, env_ids: Any) -> None:
    env.__dict__.setdefault("visual_calls", []).append("tint")


randomize_cube_tint.__module__ = "some_plugin.randomization.visual"  # a module name decides nothing


def test_visual_randomization_is_what_the_registry_or_the_functor_declares(make_env) -> None:
    from embodichain_core.plugins import hookimpl, isolated_plugins, register_plugin

    class TintPlugin:
        @hookimpl
        def embodichain_register_functors(self, register: Any) -> None:
            register("randomize_ec_loop_tint", randomize_cube_tint, kind="event", category="randomization.visual")

    tint = f"{__name__}:randomize_cube_tint"
    events = {"by_path": EventCfg(func=tint, mode="reset"), "by_func": EventCfg(func=randomize_cube_tint)}
    assert make_env(events=events, filter_visual_rand=True).event_manager.active_functors == ["by_path", "by_func"]
    with isolated_plugins():
        register_plugin(TintPlugin(), name="ec-loop-tint")
        events = {"by_name": EventCfg(func="randomize_ec_loop_tint", mode="reset"), **events}
        assert make_env(events=events, filter_visual_rand=True).event_manager.active_functors == ["by_path", "by_func"]
