"""Functor config errors name the functor and the path inside the config;
SceneEntityCfg resolution; registered functor names."""

from __future__ import annotations

from typing import Any

import pytest
import torch

from core_testlib import zero_action

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg, Functor, ObservationCfg, RewardCfg, SceneEntityCfg
from embodichain_core.plugins import hookimpl, isolated_plugins, register_plugin


def nudge_cube(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, offset: float, axis: int = 0) -> None:
    obj = env.scene[entity_cfg.uid]
    ids = torch.arange(env.num_envs) if env_ids is None else torch.as_tensor(env_ids).long()
    pose = obj.get_local_pose()[ids].clone()
    pose[:, axis] += offset
    obj.set_local_pose(pose, ids)


def sample_pose(env: Any, env_ids: Any, position_range: Any, entity_cfg: SceneEntityCfg) -> None:
    pass


def joint_obs(env: Any, obs: dict, entity_cfg: SceneEntityCfg) -> torch.Tensor:
    return env.robot.get_qpos()[:, entity_cfg.joint_ids]


def record_joints(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg) -> None:
    env.__dict__["seen_joint_ids"] = list(entity_cfg.joint_ids)


def nudge(**params: Any) -> dict:
    return {"nudge": EventCfg(func=nudge_cube, mode="reset", params=params)}


CUBE = SceneEntityCfg(uid="cube")


# -- params against the signature -----------------------------------------------------------------
def test_unknown_param_names_functor_and_path(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(events=nudge(entity_cfg=CUBE, offset=0.1, ofset=0.2))
    assert err.value.path == "env.events.nudge.params.ofset"
    assert "nudge_cube" in err.value.reason
    assert "Did you mean 'offset'" in err.value.reason


def test_missing_param_names_functor_and_param(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(events=nudge(entity_cfg=CUBE))
    assert err.value.path == "env.events.nudge.params"
    assert "nudge_cube" in err.value.reason
    assert "offset" in err.value.reason
    assert "axis" not in err.value.reason  # defaulted params are optional


def test_param_errors_in_other_sections(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(
            observations={
                "q": ObservationCfg(
                    func=joint_obs, mode="add", name="q", params={"entity_cfg": SceneEntityCfg(uid="arm"), "scale": 2}
                )
            }
        )
    assert err.value.path == "env.observations.q.params.scale"

    def reward(env: Any, obs: Any, action: Any, info: dict, target: float) -> torch.Tensor:
        return torch.zeros(env.num_envs)

    with pytest.raises(ConfigError) as err:
        make_env(rewards={"r": RewardCfg(func=reward)})
    assert err.value.path == "env.rewards.r.params"
    assert "target" in err.value.reason


def test_kwargs_functor_accepts_any_params(make_env) -> None:
    def loose(env: Any, env_ids: Any, **params: Any) -> None:
        env.__dict__["loose_params"] = params

    env = make_env(events={"loose": EventCfg(func=loose, mode="reset", params={"anything": 1})})
    env.reset()
    assert env.loose_params == {"anything": 1}


class ScaledNudge(Functor):
    def __call__(self, env: Any, env_ids: Any, scale: float) -> None:
        env.__dict__.setdefault("scaled", []).append(scale)


def test_class_functor_params(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(events={"s": EventCfg(func=ScaledNudge, mode="reset", params={"scale": 1.0, "bias": 0})})
    assert err.value.path == "env.events.s.params.bias"
    assert "ScaledNudge" in err.value.reason
    env = make_env(events={"s": EventCfg(func=ScaledNudge, mode="reset", params={"scale": 3.0})})
    env.reset()
    assert env.scaled == [3.0]


def test_class_functor_construction_failure(make_env) -> None:
    class Broken(Functor):
        def __init__(self, cfg: Any, env: Any):
            raise RuntimeError("needs a camera")

        def __call__(self, env: Any, env_ids: Any) -> None:
            pass

    with pytest.raises(ConfigError, match=r"env\.events\.b: .*Broken.*needs a camera"):
        make_env(events={"b": EventCfg(func=Broken, mode="reset")})

    class NotAFunctor:
        def __call__(self, env: Any, env_ids: Any) -> None:
            pass

    with pytest.raises(ConfigError, match=r"env\.events\.n\.func.*subclass Functor"):
        make_env(events={"n": EventCfg(func=NotAFunctor, mode="reset")})


def test_missing_or_bad_func(make_env) -> None:
    with pytest.raises(ConfigError, match=r"events\.x\.func"):
        make_env(events={"x": EventCfg(mode="reset")})
    with pytest.raises(ConfigError, match=r"env\.events\.x\.func.*cannot import"):
        make_env(events={"x": EventCfg(func="math:no_such_function", mode="reset")})
    with pytest.raises(ConfigError, match=r"env\.events\.x"):
        make_env(events={"x": "not a cfg"})


def test_module_attr_string_resolves(make_env) -> None:
    env = make_env(
        events={
            "x": EventCfg(
                func=f"{__name__}:nudge_cube", mode="reset", params={"entity_cfg": {"uid": "cube"}, "offset": 0.25}
            )
        }
    )
    env.reset()
    assert env.scene["cube"].get_local_pose()[:, 0].tolist() == pytest.approx([0.75, 0.75])


# -- ranges -------------------------------------------------------------------------------------------------
def test_inverted_range_is_rejected(make_env) -> None:
    bad = {
        "s": EventCfg(
            func=sample_pose,
            mode="reset",
            params={"entity_cfg": CUBE, "position_range": [[-0.1, 0.2, 0.0], [0.1, 0.1, 0.0]]},
        )
    }
    with pytest.raises(ConfigError) as err:
        make_env(events=bad)
    assert err.value.path == "env.events.s.params.position_range"
    assert "sample_pose" in err.value.reason
    ok = {
        "s": EventCfg(
            func=sample_pose,
            mode="reset",
            params={"entity_cfg": CUBE, "position_range": [[-0.1, 0.1, 0.0], [0.1, 0.2, 0.0]]},
        )
    }
    make_env(events=ok)


# -- SceneEntityCfg -------------------------------------------------------------------------------------------
def test_unknown_uid_suggests_the_closest(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(events=nudge(entity_cfg=SceneEntityCfg(uid="cueb"), offset=0.1))
    assert err.value.path == "env.events.nudge.params.entity_cfg.uid"
    assert "'cueb'" in err.value.reason
    assert "Did you mean 'cube'" in err.value.reason


def test_entity_dict_and_nested_entities_are_resolved(make_env) -> None:
    def pair(env: Any, env_ids: Any, targets: list) -> None:
        env.__dict__["targets"] = targets

    with pytest.raises(ConfigError) as err:
        make_env(
            events={
                "p": EventCfg(
                    func=pair,
                    mode="reset",
                    params={"targets": [SceneEntityCfg(uid="cube"), SceneEntityCfg(uid="tabel")]},
                )
            }
        )
    assert err.value.path == "env.events.p.params.targets[1].uid"
    assert "'table'" in err.value.reason
    env = make_env(events=nudge(entity_cfg={"uid": "cube"}, offset=0.1))
    resolved = env.event_manager.get_functor_cfg("nudge").params["entity_cfg"]
    assert isinstance(resolved, SceneEntityCfg)
    assert resolved.uid == "cube"


def test_joint_names_resolve_to_ids(make_env) -> None:
    env = make_env(
        events={
            "r": EventCfg(
                func=record_joints,
                mode="reset",
                params={"entity_cfg": SceneEntityCfg(uid="arm", joint_names=["joint[2-4]"])},
            )
        },
        observations={
            "q": ObservationCfg(
                func=joint_obs,
                mode="add",
                name="fingers",
                params={"entity_cfg": SceneEntityCfg(uid="arm", joint_names="finger_.*")},
            )
        },
    )
    env.reset()
    assert env.seen_joint_ids == [1, 2, 3]
    assert env.observation_manager.get_functor_cfg("q").params["entity_cfg"].joint_ids == [7, 8]
    obs, *_ = env.step(zero_action(env))
    assert obs["fingers"].shape == (2, 2)
    ordered = SceneEntityCfg(uid="arm", joint_names=["joint3", "joint1"], preserve_order=True).resolve(env.scene)
    assert list(ordered.joint_ids) == [2, 0]
    assert list(SceneEntityCfg(uid="arm", joint_names=["joint3", "joint1"]).resolve(env.scene).joint_ids) == [0, 2]


def test_joint_names_that_match_nothing(make_env) -> None:
    with pytest.raises(ConfigError) as err:
        make_env(
            events={
                "r": EventCfg(
                    func=record_joints,
                    mode="reset",
                    params={"entity_cfg": SceneEntityCfg(uid="arm", joint_names=["elbow_.*"])},
                )
            }
        )
    assert err.value.path == "env.events.r.params.entity_cfg.joint_names"
    assert "elbow_" in err.value.reason


def test_joint_names_and_ids_must_agree(make_env) -> None:
    with pytest.raises(ConfigError, match="disagrees"):
        make_env(
            events={
                "r": EventCfg(
                    func=record_joints,
                    mode="reset",
                    params={"entity_cfg": SceneEntityCfg(uid="arm", joint_names=["joint1"], joint_ids=[3])},
                )
            }
        )


def test_joint_names_on_an_entity_without_joints(make_env) -> None:
    with pytest.raises(ConfigError, match=r"env\.events\.r\.params\.entity_cfg.*no joints"):
        make_env(
            events={
                "r": EventCfg(
                    func=record_joints,
                    mode="reset",
                    params={"entity_cfg": SceneEntityCfg(uid="point", joint_names=["x"])},
                )
            }
        )


# -- registered functors ----------------------------------------------------------------------------------------
def ec_test_lift_cube(env: Any, env_ids: Any, entity_cfg: SceneEntityCfg, dz: float) -> None:
    obj = env.scene[entity_cfg.uid]
    pose = obj.get_local_pose()[env_ids].clone()
    pose[:, 2] += dz
    obj.set_local_pose(pose, env_ids)


class LiftPlugin:
    @hookimpl
    def embodichain_register_functors(self, register: Any) -> None:
        register("ec_test_lift_cube", ec_test_lift_cube, kind="event", category="randomization.spatial")
        register("ec_test_cube_height", f"{__name__}:joint_obs", kind="observation")


def test_registered_functor_name_resolves_and_unknown_suggests() -> None:
    from core_testlib import base_cfg
    from embodichain_core.envs import EmbodiedEnv

    with isolated_plugins():
        register_plugin(LiftPlugin(), name="ec-test-lift")
        cfg = base_cfg(
            events={
                "lift": EventCfg(
                    func="ec_test_lift_cube", mode="reset", params={"entity_cfg": {"uid": "cube"}, "dz": 0.5}
                )
            }
        )
        env = EmbodiedEnv(cfg)
        env.reset()
        assert env.scene["cube"].get_local_pose()[:, 2].tolist() == pytest.approx([0.55, 0.55])
        cfg.events["lift"].func = "ec_test_lift_cub"
        with pytest.raises(ConfigError) as err:
            EmbodiedEnv(cfg)
        assert err.value.path == "env.events.lift.func"
        assert "unknown event functor 'ec_test_lift_cub'" in err.value.reason
        assert "Did you mean 'ec_test_lift_cube'" in err.value.reason
    cfg.events["lift"].func = "ec_test_lift_cube"
    with pytest.raises(ConfigError, match="ec_test_lift_cube"):  # gone with the isolated plugins
        EmbodiedEnv(cfg)


def test_entity_params_are_found_by_annotation(make_env) -> None:
    """A param annotated ``SceneEntityCfg`` (or a list of it) names entities whatever its
    name; an unannotated one not named ``*entity_cfg`` is left as given."""

    def place(env: Any, env_ids: Any, goal: SceneEntityCfg, others: list[SceneEntityCfg], tag: Any = None) -> None:
        env.__dict__["placed"] = (goal, others, tag)

    def event(**params: Any) -> dict:
        return {"p": EventCfg(func=place, mode="reset", params={"others": [], **params})}

    env = make_env(events=event(goal={"uid": "cube"}, others=[{"uid": "table"}], tag={"uid": "cube"}))
    env.reset()
    goal, others, tag = env.placed
    assert isinstance(goal, SceneEntityCfg)
    assert goal.uid == "cube"
    assert isinstance(others[0], SceneEntityCfg)
    assert others[0].uid == "table"
    assert tag == {"uid": "cube"}  # not an entity param: a plain mapping
    with pytest.raises(ConfigError) as err:
        make_env(events=event(goal={"uid": "cueb"}))
    assert err.value.path == "env.events.p.params.goal.uid"
    assert "Did you mean 'cube'" in err.value.reason
    with pytest.raises(ConfigError) as err:
        make_env(events=event(goal={"uid": "cube"}, others=[{"uid": "cube"}, {"uid": "tabel"}]))
    assert err.value.path == "env.events.p.params.others[1].uid"
    with pytest.raises(ConfigError, match="expected an entity"):
        make_env(events=event(goal="cube"))
