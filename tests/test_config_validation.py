"""Config validation at build (no plugin): value checks, physical values of the scene,
manager sections and event modes, functor params by naming convention, the memory
estimate, and the observation ``modify`` of a missing key."""

from __future__ import annotations

import math
import warnings
from typing import Any

import pytest

from core_testlib import base_cfg

from embodichain_core.config.checks import check_int, check_number, check_range, check_vector
from embodichain_core.config.errors import ConfigError
from embodichain_core.config.loader import load_gym_config
from embodichain_core.config.resources import MEMORY_LIMIT_ENV, available_memory, check_memory, estimate_memory
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.managers import EventCfg, ObservationCfg, SceneEntityCfg
from embodichain_core.managers.event_manager import check_event_mode
from embodichain_core.managers.param_rules import check_named_params, check_param_types
from embodichain_core.sim.cfg import LightCfg, SensorCfg
from embodichain_core.utils.configclass import configclass


def nudge(env: Any, env_ids: Any, entity_cfg: Any, offset_range: Any = (0.0, 0.1), relative: bool = False) -> None:
    """An event functor of the tests (does nothing)."""


def raise_path(fn: Any, *args: Any, **kwargs: Any) -> ConfigError:
    with pytest.raises(ConfigError) as err:
        fn(*args, **kwargs)
    return err.value


# -- value checks ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "value, expected",
    [
        ("x", "expected a finite number"),
        (math.nan, "finite"),
        (math.inf, "finite"),
        (True, "got bool"),
        (-1.0, "must be >= 0"),
    ],
)
def test_check_number_rejects(value: Any, expected: str) -> None:
    err = raise_path(check_number, value, "attrs.mass", low=0.0)
    assert err.path == "attrs.mass"
    assert expected in err.reason


def test_check_vector_names_the_item_and_the_length() -> None:
    assert raise_path(check_vector, [0, 0], 3, "init_pos").reason.startswith("expected 3 finite numbers")
    assert raise_path(check_vector, [0, math.nan, 0], 3, "init_pos").path == "init_pos[1]"
    assert raise_path(check_vector, {"x": 1}, 3, "init_pos").path == "init_pos"
    assert check_vector((1, 2, 3), 3, "p") == [1.0, 2.0, 3.0]


def test_check_range_rules() -> None:
    assert "above high" in raise_path(check_range, [2, 1], "r").reason
    assert "pair" in raise_path(check_range, [1], "r").reason
    assert raise_path(check_range, [[0, 0], [1, 1, 1]], "r").reason.startswith("low and high have different")
    assert "finite" in raise_path(check_range, [0, math.inf], "r").reason
    assert "in [0, 1]" in raise_path(check_range, [0.5, 1.5], "r", low=0.0, high=1.0).reason
    low, high = check_range([[0, 0, 0], [1, 2, 3]], "r", width=3)
    assert low.tolist() == [0, 0, 0]
    assert high.tolist() == [1, 2, 3]


def test_check_int_bounds_and_types() -> None:
    assert check_int(3, "n") == 3
    assert "1000000" in raise_path(check_int, 10**7, "num_envs", high=10**6).reason
    assert "got float 2.5" in raise_path(check_int, 2.5, "n").reason


# -- physical values of the scene --------------------------------------------------------------------
def _set(cfg: Any, path: list, value: Any) -> Any:
    node = cfg
    for key in path[:-1]:
        node = node[key] if isinstance(key, int) else getattr(node, key)
    setattr(node, path[-1], value)
    return cfg


@pytest.mark.parametrize(
    "path, value, where",
    [
        (["rigid_object", 0, "attrs", "mass"], -0.1, "rigid_object[0].attrs.mass"),
        (["rigid_object", 0, "attrs", "static_friction"], -0.5, "rigid_object[0].attrs.static_friction"),
        (["rigid_object", 0, "attrs", "restitution"], 1.5, "rigid_object[0].attrs.restitution"),
        (["rigid_object", 0, "attrs", "min_position_iters"], 0, "rigid_object[0].attrs.min_position_iters"),
        (["rigid_object", 0, "body_scale"], (1.0, 0.0, 1.0), "rigid_object[0].body_scale[1]"),
        (["rigid_object", 0, "body_scale"], (1.0, 1.0), "rigid_object[0].body_scale"),
        (["rigid_object", 0, "init_pos"], (0.0, math.nan, 0.0), "rigid_object[0].init_pos[1]"),
        (["rigid_object", 0, "init_rot"], (0.0, 0.0, 0.0, 1.0), "rigid_object[0].init_rot"),
        (["rigid_object", 0, "shape", "size"], [0.05, 0.05], "rigid_object[0].shape.size"),
        (["background", 0, "attrs", "dynamic_friction"], math.inf, "background[0].attrs.dynamic_friction"),
        (["light", "direct", 0, "intensity"], -1.0, "light.direct[0].intensity"),
        (["light", "direct", 0, "color"], (1.5, 1.0, 1.0), "light.direct[0].color[0]"),
        (["robot", "init_qpos"], [0.0] * 6 + [math.nan, 0.0, 0.0], "robot.init_qpos[6]"),
        (["robot", "drive_pros", "damping"], {"joint1": -5.0}, "robot.drive_pros.damping.joint1"),
        (["sim_cfg", "physics_config", "iterations"], 0, "sim_cfg.physics_config.iterations"),
        (["sim_cfg", "physics_substeps"], 10**6, "sim_cfg.physics_substeps"),
    ],
)
def test_physical_values_fail_before_the_scene_is_built(monkeypatch, path: list, value: Any, where: str) -> None:
    import embodichain_core.envs.embodied_env as embodied

    monkeypatch.setattr(embodied, "add_config_entities", lambda *a: pytest.fail("the scene was built"))
    err = raise_path(EmbodiedEnv, _set(base_cfg(), path, value))
    assert err.path == where, err


def test_zero_mass_takes_the_mass_from_density(make_env) -> None:
    cfg = _set(base_cfg(), ["rigid_object", 0, "attrs", "mass"], 0.0)
    env = make_env(cfg)
    assert float(env.scene.model.body_mass[env.scene["cube"].body_id]) > 0
    cfg = _set(_set(base_cfg(), ["rigid_object", 0, "attrs", "mass"], 0.0), ["rigid_object", 0, "attrs", "density"], 0)
    assert raise_path(cfg.validate).path == "rigid_object[0].attrs.density"


def test_light_ambient_and_group_values() -> None:
    cfg = base_cfg()
    cfg.light.indirect = {"ambient": [0.3, 0.3, 2.0]}
    assert raise_path(cfg.validate).path == "light.indirect.ambient[2]"
    cfg = base_cfg(light=base_cfg().EnvLightCfg(direct=[LightCfg(uid="l", direction=(0.0, 0.0, 0.0))]))
    assert raise_path(cfg.validate).path == "light.direct[0].direction"


# -- manager sections and event modes ---------------------------------------------------------------
@pytest.mark.parametrize(
    "mode, declared, near",
    [
        ("rset", [], "reset"),
        ("intervall", [], "interval"),
        ("Reset", [], "reset"),
        ("rseet", [], "reset"),
        ("atach", ["attach"], "attach"),
        ("attach", [], None),
        ("every_step", [], None),
    ],
)
def test_event_mode_typos_are_told_from_undeclared_modes(mode: str, declared: list, near: Any) -> None:
    reason = raise_path(check_event_mode, mode, "env.events.x", declared).reason
    if near is None:
        assert "Did you mean" not in reason
        assert "must be declared in env.custom_event_modes" in reason
    else:
        assert f"Did you mean {near!r}" in reason


@pytest.mark.parametrize(
    "mode, suggestion", [("rset", "reset"), ("intervall", "interval"), ("startp", "startup"), (" reset", "reset")]
)
def test_a_typo_of_an_event_mode_is_an_error_with_the_suggestion(mode: str, suggestion: str) -> None:
    cfg = base_cfg(events={"move": EventCfg(func=nudge, mode=mode, params={"entity_cfg": {"uid": "cube"}})})
    err = raise_path(cfg.validate)
    assert err.path == "env.events.move.mode"
    assert f"Did you mean {suggestion!r}" in err.reason


def test_declared_custom_modes(make_env) -> None:
    events = {"lift": EventCfg(func=nudge, mode="resets", params={"entity_cfg": {"uid": "cube"}})}
    assert "Did you mean 'reset'" in raise_path(base_cfg(events=events).validate).reason
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = make_env(base_cfg(events=events, custom_event_modes=["resets"]))
    assert env.event_manager.functors_of("resets") == ["lift"]
    cfg = base_cfg(
        events={"x": EventCfg(func=nudge, mode="atach", params={"entity_cfg": {"uid": "cube"}})},
        custom_event_modes=["attach"],
    )
    assert "Did you mean 'attach'" in raise_path(cfg.validate).reason
    assert raise_path(base_cfg(custom_event_modes=["reset"]).validate).path == "env.custom_event_modes[0]"


@pytest.mark.parametrize("mode", ["attach", "sometimes", "SOMETIMES", "every_step"])
def test_an_undeclared_mode_is_an_error_whatever_its_spelling(mode: str) -> None:
    with pytest.raises(ConfigError, match="custom_event_modes") as info:
        check_event_mode(mode, "env.events.x")
    assert info.value.path == "env.events.x.mode"
    check_event_mode(mode, "env.events.x", declared=[mode])  # declared: allowed


def test_a_functor_may_declare_its_modes() -> None:

    def weld(env: Any, env_ids: Any) -> None:
        """A functor declaring the custom mode it runs in."""

    weld.event_modes = ("weld",)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        base_cfg(events={"w": EventCfg(func=weld, mode="weld")}).validate()


def test_interval_steps_are_bounded_and_warn_when_they_never_fire(make_env) -> None:
    event = EventCfg(func=nudge, mode="interval", interval_step=500, params={"entity_cfg": {"uid": "cube"}})
    with pytest.warns(UserWarning, match="never fires"):
        make_env(events={"tick": event}, max_episode_steps=100)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        make_env(events={"tick": event.replace(is_global=True)}, max_episode_steps=100)
    assert raise_path(base_cfg(events={"tick": event.replace(interval_step=0)}).validate).path.endswith("interval_step")
    too_big = event.replace(interval_step=10**9, mode="reset")
    assert "10000000" in raise_path(base_cfg(events={"tick": too_big}).validate).reason


@pytest.mark.parametrize(
    "params, where",
    [
        ({}, "env.events.e.params"),
        ({"entity_cfg": {"uid": "cub"}}, "env.events.e.params.entity_cfg.uid"),
        ({"entity_cfg": "cube"}, "env.events.e.params.entity_cfg"),
        ({"entity_cfg": {"uid": "cube"}, "offset_range": [0.2, 0.1]}, "env.events.e.params.offset_range"),
        ({"entity_cfg": {"uid": "cube"}, "relative": "yes"}, "env.events.e.params.relative"),
        ({"entity_cfg": {"uid": "cube"}, "ofset_range": [0, 1]}, "env.events.e.params.ofset_range"),
    ],
)
def test_event_params_are_checked_before_the_build(params: dict, where: str) -> None:
    err = raise_path(base_cfg(events={"e": EventCfg(func=nudge, params=params)}).validate)
    assert err.path == where, err
    if where.endswith(".uid"):
        assert "Did you mean 'cube'" in err.reason


def test_observation_entries() -> None:
    bad_mode = {"o": ObservationCfg(func=nudge, mode="ad", name="x", params={"entity_cfg": {"uid": "cube"}})}
    assert "Did you mean 'add'" in raise_path(base_cfg(observations=bad_mode).validate).reason
    no_level = {"o": ObservationCfg(func=nudge, mode="add", name="a//b", params={"entity_cfg": {"uid": "cube"}})}
    assert raise_path(base_cfg(observations=no_level).validate).path == "env.observations.o.name"


def test_an_observation_name_must_not_shadow_a_group() -> None:
    params = {"entity_cfg": {"uid": "cube"}}
    for group in ("robot", "sensor"):
        shadow = {"o": ObservationCfg(func=nudge, mode="add", name=group, params=params)}
        err = raise_path(base_cfg(observations=shadow).validate)
        assert err.path == "env.observations.o.name"
        assert "observation group" in err.reason
    nested = {
        "pose": ObservationCfg(func=nudge, mode="add", name="object/cube_pose", params=params),
        "whole": ObservationCfg(func=nudge, mode="add", name="object", params=params),
    }
    err = raise_path(base_cfg(observations=nested).validate)
    assert err.path == "env.observations.whole.name"
    assert "'object/cube_pose'" in err.reason
    members = {"o": ObservationCfg(func=nudge, mode="add", name="robot/extra", params=params)}
    base_cfg(observations=members).validate()  # a member of a group is fine


def double(env: Any, data: Any) -> Any:
    """An observation functor of the tests."""
    return data * 2


def test_modify_of_a_missing_observation_is_a_config_error_at_build(make_env) -> None:
    observations = {"twice": ObservationCfg(func=double, mode="modify", name="robot/joint_pos")}
    with pytest.raises(ConfigError) as err:
        make_env(observations=observations)
    assert err.value.path == "env.observations.twice.name"
    assert "mode 'modify'" in err.value.reason
    env = make_env(observations={"twice": ObservationCfg(func=double, mode="modify", name="robot/qpos")})
    assert env.observation_manager.active_functors == ["twice"]


# -- functor params by naming convention ---------------------------------------------------------
@pytest.mark.parametrize(
    "params, key, text",
    [
        ({"mass_range": [0.5, 0.1]}, "mass_range", "above high"),
        ({"mass_range": [0.0, 0.1]}, "mass_range", "> 0"),
        ({"friction_range": [-0.1, 0.5]}, "friction_range", ">= 0"),
        ({"color_range": [[0.1] * 3, [1.2] * 3]}, "color_range", "in [0, 1]"),
        ({"base_color_range": [[0.1, 0.1], [1, 1]]}, "base_color_range[0]", "RGB"),
        ({"scale_factor_range": [0.0, 1.0]}, "scale_factor_range", "> 0"),
        ({"random_texture_prob": 1.5}, "random_texture_prob", "probability"),
        ({"mass_range": {"link1": [2.0, 1.0]}}, "mass_range.link1", "above high"),
        ({"strength": [1.0, math.nan]}, "strength[1]", "NaN"),
        ({"position_range": "far"}, "position_range", "[low, high]"),
    ],
)
def test_named_params(params: dict, key: str, text: str) -> None:
    err = raise_path(check_named_params, params, "env.events.e", "f")
    assert err.path == f"env.events.e.params.{key}"
    assert text in err.reason
    assert "functor 'f'" in err.reason


@pytest.mark.parametrize(
    "params, key",
    [
        ({"position_range": [[-1e9, 0.0, 0.0], [0.1, 0.0, 0.0]]}, "position_range"),
        ({"intensity_range": [1.0, 1e12]}, "intensity_range"),
        ({"mass_range": [0.1, 2e6], "relative": True}, "mass_range"),
        ({"damping_range": {"link1": [0.0, 1e7]}}, "damping_range.link1"),
    ],
)
def test_a_range_bound_of_huge_magnitude_is_an_error(params: dict, key: str) -> None:
    err = raise_path(check_named_params, params, "env.events.e", "f")
    assert err.path == f"env.events.e.params.{key}"
    assert "magnitude above 1e+06" in err.reason
    check_named_params({"position_range": [[-1e6, 0.0, 0.0], [1e6, 0.0, 0.0]]}, "env.events.e", "f")  # at the bound


@pytest.mark.parametrize(
    "edit, path, quantity",
    [
        (lambda c: setattr(c.rigid_object[0], "init_pos", (0.5, 2e6, 0.5)), "rigid_object[0].init_pos[1]", "position"),
        (lambda c: setattr(c.background[0], "init_pos", (-1e6, 0.0, 0.0)), "background[0].init_pos[0]", "position"),
        (lambda c: setattr(c.robot, "init_pos", (0.0, 0.0, 5e5)), "robot.init_pos[2]", "position"),
        (lambda c: setattr(c.rigid_object[0].attrs, "mass", 1e6), "rigid_object[0].attrs.mass", "mass"),
        (lambda c: setattr(c.background[0].attrs, "density", 1e9), "background[0].attrs.density", "density"),
        (
            lambda c: setattr(c.rigid_object[0].attrs, "static_friction", 1e6),
            "rigid_object[0].attrs.static_friction",
            "friction",
        ),
        (lambda c: setattr(c.robot.attrs, "dynamic_friction", 1e9), "robot.attrs.dynamic_friction", "friction"),
    ],
)
def test_implausible_physical_scales_are_errors_with_an_override(edit: Any, path: str, quantity: str) -> None:
    cfg = base_cfg()
    edit(cfg)
    err = raise_path(cfg.validate, memory=False)
    assert err.path == path
    assert f"sim_cfg.physical_limits.{quantity}" in err.reason
    cfg.sim_cfg.physical_limits = {quantity: 1e10}
    cfg.validate(memory=False)  # the documented override


def test_physical_limits_must_name_known_quantities() -> None:
    cfg = base_cfg()
    cfg.sim_cfg.physical_limits = {"speed": 3.0}
    assert raise_path(cfg.validate, memory=False).path == "sim_cfg.physical_limits.speed"
    cfg.sim_cfg.physical_limits = {"mass": -1.0}
    assert raise_path(cfg.validate, memory=False).path == "sim_cfg.physical_limits.mass"


def test_named_params_accept_relative_and_optional_ranges() -> None:
    check_named_params({"mass_range": [-0.1, 0.1], "relative": True, "intensity_range": None}, "e", "f")
    check_named_params({"intensity_range": [-5.0, 5.0], "position_range": [[0, 0, 0], [1, 1, 1]]}, "e", "f")


def test_param_types_follow_the_signature() -> None:
    check_param_types(nudge, {"relative": True, "entity_cfg": SceneEntityCfg(uid="cube")}, "e", 2)
    err = raise_path(check_param_types, nudge, {"relative": 1}, "env.events.e", 2)
    assert err.path == "env.events.e.params.relative"
    assert "true/false" in err.reason


# -- memory estimate -------------------------------------------------------------------------------
@configclass
class FakeCameraCfg(SensorCfg):
    """A sensor config reporting its buffer size, as camera configs do."""

    sensor_type: str = "FakeCamera"
    width: int = 640
    height: int = 480

    def buffer_bytes_per_env(self) -> int:
        return self.width * self.height * 4


def test_memory_estimate_counts_envs_and_sensor_buffers() -> None:
    cfg = base_cfg(sensor=[FakeCameraCfg(uid="cam")])
    small, large = estimate_memory(cfg, 2), estimate_memory(cfg, 20)
    assert large.parts["sensor[0] (FakeCamera)"] == 10 * small.parts["sensor[0] (FakeCamera)"] == 2 * 20 * 640 * 480 * 4
    assert large.total > small.total
    assert "simulation" in large.parts


def test_memory_limit_fails_fast_with_the_fields_to_change(monkeypatch) -> None:
    cfg = base_cfg(sensor=[FakeCameraCfg(uid="cam", width=4096, height=4096)], num_envs=64)
    monkeypatch.setenv(MEMORY_LIMIT_ENV, "1")
    err = raise_path(check_memory, cfg)
    assert err.path == "sensor[0]"
    assert "sensor[0].width" in err.reason
    assert MEMORY_LIMIT_ENV in err.reason
    assert "GB" in err.reason
    assert "num_envs=64" in err.reason
    monkeypatch.setenv(MEMORY_LIMIT_ENV, "0")  # disabled
    check_memory(cfg)
    monkeypatch.setenv(MEMORY_LIMIT_ENV, "lots")
    assert MEMORY_LIMIT_ENV in str(raise_path(check_memory, cfg))


def test_memory_check_runs_before_anything_is_allocated(monkeypatch) -> None:
    import embodichain_core.envs.embodied_env as embodied

    monkeypatch.setattr(embodied, "add_config_entities", lambda *a: pytest.fail("the scene was built"))
    monkeypatch.setenv(MEMORY_LIMIT_ENV, "0.001")
    assert raise_path(EmbodiedEnv, base_cfg(num_envs=64)).path == "num_envs"
    monkeypatch.delenv(MEMORY_LIMIT_ENV)
    assert "1000000" in raise_path(EmbodiedEnv, base_cfg(num_envs=10**7)).reason


def test_available_memory_reads_the_machine() -> None:
    size, source = available_memory()
    assert size is None or size > 0 and source


# -- loader ------------------------------------------------------------------------------------------
def _file_cfg(**env: Any) -> dict:
    from scenes import seven_dof_arm_mjcf

    return {"id": "T-v0", "robot": {"uid": "arm", "mjcf": seven_dof_arm_mjcf()}, "env": env}


def test_loader_errors_name_the_nested_key() -> None:
    data = _file_cfg(dataset={"rec": {"mode": "save", "params": {"out": "x"}}})
    assert raise_path(load_gym_config, data).path == "env.dataset.rec.func"
    data = {**_file_cfg(), "robot": {"uid": "arm", "drive_pros": {"stiffness": {"joint1": "stiff"}}}}
    assert raise_path(load_gym_config, data).path == "robot.drive_pros.stiffness.joint1"


@configclass
class CheckedCfg:
    """A config checking itself on construction, naming only its own field."""

    width: int = 1

    def __post_init__(self) -> None:
        if self.width < 1:
            raise ConfigError("width", f"must be >= 1, got {self.width}")


def test_a_self_check_of_a_nested_config_gets_its_path() -> None:
    from typing import List

    from embodichain_core.config.convert import convert_value

    err = raise_path(convert_value, [{"width": 2}, {"width": 0}], List[CheckedCfg], "sensor")
    assert err.path == "sensor[1].width"


def test_entity_uids_are_unique_before_the_build() -> None:
    cfg = base_cfg()
    cfg.background[0].uid = "cube"
    err = raise_path(cfg.validate)
    assert err.path == "rigid_object[0].uid"
    assert "background[0]" in err.reason
    cfg.background[0].uid = "default_plane"
    assert "ground plane" in raise_path(cfg.validate).reason


def test_the_loader_bounds_num_envs_before_the_env_allocates_anything() -> None:
    err = raise_path(load_gym_config, {**_file_cfg(), "num_envs": 10**9})
    assert err.path == "num_envs"
    assert "1000000" in err.reason
    assert raise_path(load_gym_config, _file_cfg(), {"num_envs": 0}).path == "num_envs"


def test_init_qpos_of_the_wrong_length_names_the_key(make_env, make_cfg) -> None:
    cfg = make_cfg()
    cfg.robot.init_qpos = [0.0, 0.1]
    with pytest.raises(ConfigError, match=r"^robot\.init_qpos: 'arm' has 9 joints") as err:
        make_env(cfg)
    assert "got 2 values" in str(err.value)
