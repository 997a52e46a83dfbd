"""JSON/YAML gym configs -> ``EmbodiedEnvCfg`` (embodichain_core.config.loader)."""

from __future__ import annotations

import copy
import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest
import torch
import yaml

from scenes import ARM_MJCF, seven_dof_arm_mjcf

from embodichain_core.config.errors import ConfigError
from embodichain_core.config.loader import (
    SCENE_SECTIONS,
    apply_overrides,
    gym_config_to_cfg,
    load_config_file,
    load_gym_config,
)
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.managers.cfg import ActionTermCfg, DatasetFunctorCfg, EventCfg, ObservationCfg, RewardCfg
from embodichain_core.plugins import hookimpl
from embodichain_core.sim.shapes import CubeCfg

CALLS: list[tuple[str, Any]] = []


def count_event(env: Any, env_ids: Any, tag: str = "x") -> None:
    """Event functor of these tests: records its calls."""
    CALLS.append((tag, env_ids))


def gym_config(**top: Any) -> dict:
    """A small valid gym config (3-DoF arm, a cube, a kinematic table, a light)."""
    data = {
        "id": "LoaderTest-v0",
        "max_episodes": 3,
        "num_envs": 2,
        "max_episode_steps": 20,
        "env": {
            "seed": 1,
            "verbose": False,
            "events": {
                "tick": {
                    "func": f"{__name__}:count_event",
                    "mode": "interval",
                    "interval_step": 2,
                    "is_global": True,
                    "params": {"tag": "t"},
                }
            },
            "dataset": {"robot_meta": {"robot_type": "Arm3"}},
        },
        "robot": {"uid": "arm", "mjcf": ARM_MJCF},
        "light": {"direct": [{"uid": "lamp", "light_type": "point", "init_pos": [0, 0, 2]}]},
        "background": [
            {"uid": "table", "shape": {"shape_type": "Cube", "size": [0.4, 0.4, 0.2]}, "init_pos": [0.6, 0, 0.1]}
        ],
        "rigid_object": [
            {"uid": "cube", "shape": {"shape_type": "Cube", "size": [0.05, 0.05, 0.05]}, "init_pos": [0.5, 0.0, 0.3]}
        ],
    }
    data.update(top)
    return data


def config_error(data: dict) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        gym_config_to_cfg(data)
    return info.value


def test_json_and_yaml_load_to_equal_cfgs(tmp_path: Path) -> None:
    data = gym_config()
    (tmp_path / "c.json").write_text(json.dumps(data))
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(data))
    id_json, cfg_json, extras_json = load_gym_config(tmp_path / "c.json")
    id_yaml, cfg_yaml, extras_yaml = load_gym_config(str(tmp_path / "c.yaml"))
    assert cfg_json == cfg_yaml == load_gym_config(data)[1]
    assert id_json == id_yaml == "LoaderTest-v0"
    assert extras_json == extras_yaml == {"id": "LoaderTest-v0", "max_episodes": 3, "demo_max_attempts": 3}
    assert cfg_json.num_envs == 2
    assert cfg_json.max_episode_steps == 20
    assert cfg_json.seed == 1
    assert isinstance(cfg_json.rigid_object[0].shape, CubeCfg)
    assert cfg_json.background[0].body_type == "static"  # background default
    assert cfg_json.light.direct[0].uid == "lamp"
    event = cfg_json.events["tick"]
    assert isinstance(event, EventCfg)
    assert event.is_global
    assert event.interval_step == 2
    assert event.func == f"{__name__}:count_event"  # kept as given; managers resolve it
    assert cfg_json.dataset == {"robot_meta": {"robot_type": "Arm3"}}  # plain metadata kept


def test_cfg_from_file_builds_an_env() -> None:
    _, cfg, _ = load_gym_config(gym_config(physics_dt=0.005))
    CALLS.clear()
    env = EmbodiedEnv(cfg)
    try:
        assert env.num_envs == 2
        assert env.physics_dt == 0.005
        assert env.cfg.seed == 1
        env.reset()
        for _ in range(4):
            env.step(torch.zeros(env.action_space.shape))
        assert [tag for tag, _ in CALLS] == ["t", "t"]  # every 2nd step, one global counter
    finally:
        env.close()


#: A value for every non-scene field of EmbodiedEnvCfg, and where it goes in the file.
ENV_FIELDS: dict[str, Any] = {
    "custom_event_modes": ["attach"],
    "num_envs": 3,
    "seed": 7,
    "sim_steps_per_control": 2,
    "target_control_frequency": 50.0,
    "ignore_terminations": True,
    "max_episode_steps": 9,
    "verbose": False,
    "control_parts": ["arm"],
    "active_joint_ids": [0, 1],
    "filter_visual_rand": True,
    "filter_dataset_saving": True,
    "init_rollout_buffer": True,
    "strict_actions": True,
    "extensions": {"goal": [1, 2]},
    "sim_cfg": {"width": 320, "cpu_num": 2},
    "events": {"e": {"func": "f", "mode": "interval", "interval_step": 3, "is_global": True}},
    "observations": {"o": {"func": "g", "mode": "add", "name": "task/goal", "extra": {"shape": [3]}}},
    "rewards": {"r": {"func": "h", "mode": "replace", "weight": 0.5}},
    "actions": {"a": {"func": "k", "mode": "post", "params": {"scale": 0.1}}},
    "dataset": {"d": {"func": "rec", "save_failed_episodes": True}, "robot_meta": {"name": "arm"}},
}
SIM_KEYS = {
    "headless": False,
    "device": "cpu",
    "gpu_id": 1,
    "arena_space": 3.0,
    "physics_dt": 0.002,
    "physics_substeps": 2,
    "physics_config": {"gravity": [0, 0, -1.0], "solver": "CG"},
    "render_cfg": {"quality": "high", "renderer": "fast"},
    "renderer": "rt",
    "physical_limits": {"mass": 1e5},
}


def test_every_cfg_field_is_settable_from_a_file() -> None:
    fields = {f.name for f in dataclasses.fields(EmbodiedEnvCfg)}
    assert fields == set(ENV_FIELDS) | set(SCENE_SECTIONS), "a new cfg field needs a line in ENV_FIELDS"
    cfg, _ = gym_config_to_cfg(_without(gym_config(env=copy.deepcopy(ENV_FIELDS), **SIM_KEYS)))
    for name in (
        "num_envs",
        "seed",
        "sim_steps_per_control",
        "target_control_frequency",
        "ignore_terminations",
        "max_episode_steps",
        "verbose",
        "control_parts",
        "active_joint_ids",
        "filter_visual_rand",
        "filter_dataset_saving",
        "init_rollout_buffer",
        "strict_actions",
        "extensions",
    ):
        assert getattr(cfg, name) == ENV_FIELDS[name], name
    assert cfg.sim_cfg.physical_limits == {"mass": 1e5}
    assert (cfg.sim_cfg.width, cfg.sim_cfg.cpu_num, cfg.sim_cfg.headless, cfg.sim_cfg.sim_device) == (
        320,
        2,
        False,
        "cpu",
    )
    assert (cfg.sim_cfg.gpu_id, cfg.sim_cfg.arena_space, cfg.sim_cfg.physics_dt) == (1, 3.0, 0.002)
    assert cfg.sim_cfg.physics_substeps == 2
    assert cfg.sim_cfg.physics_config.gravity == (0, 0, -1.0)
    assert cfg.sim_cfg.physics_config.solver == "CG"
    assert cfg.sim_cfg.render_cfg.quality == "high"
    assert cfg.sim_cfg.render_cfg.renderer == "rt"  # the flat key overrides render_cfg.renderer
    assert cfg.events["e"] == EventCfg(func="f", mode="interval", interval_step=3, is_global=True)
    assert cfg.observations["o"] == ObservationCfg(func="g", mode="add", name="task/goal", extra={"shape": [3]})
    assert cfg.rewards["r"] == RewardCfg(func="h", mode="replace", weight=0.5)
    assert cfg.actions["a"] == ActionTermCfg(func="k", mode="post", params={"scale": 0.1})
    assert cfg.dataset["d"] == DatasetFunctorCfg(func="rec", save_failed_episodes=True)
    assert cfg.dataset["robot_meta"] == {"name": "arm"}


def _without(data: dict) -> dict:
    """``data`` without the top-level keys that ENV_FIELDS sets inside ``env``."""
    return {k: v for k, v in data.items() if k not in ("num_envs", "max_episode_steps")}


@pytest.mark.parametrize(
    "mutate, path, hint",
    [
        (lambda d: d["env"].update(evnts={}), "env.evnts", "Did you mean 'events'"),
        (lambda d: d["rigid_object"][0].update(shpe={}), "rigid_object[0].shpe", "Did you mean 'shape'"),
        (lambda d: d.update(robto={}), "robto", "Did you mean 'robot'"),
        (
            lambda d: d["env"]["events"]["tick"].update(intervl_step=3),
            "env.events.tick.intervl_step",
            "Did you mean 'interval_step'",
        ),
        (lambda d: d.update(sim_cfg={"physics_dtt": 0.1}), "sim_cfg.physics_dtt", "Did you mean 'physics_dt'"),
        (lambda d: d.update(seed=3), "seed", "belongs inside 'env'"),
        (lambda d: d["env"].update(robot={}), "env.robot", "top-level section"),
        (lambda d: d["env"].update(num_envs=4), "env.num_envs", "also given at num_envs"),
    ],
)
def test_unknown_or_misplaced_keys_name_path_and_suggest(mutate: Any, path: str, hint: str) -> None:
    data = gym_config()
    mutate(data)
    err = config_error(data)
    assert err.path == path
    assert hint in str(err)


@pytest.mark.parametrize(
    "mutate, path",
    [
        (lambda d: d["env"]["events"]["tick"].update(interval_step="ten"), "env.events.tick.interval_step"),
        (lambda d: d.update(physics_dt="fast"), "physics_dt"),
        (lambda d: d.update(device=0), "device"),
        (lambda d: d.update(physics_config={"solver": "Newtn"}), "physics_config.solver"),
        (lambda d: d["rigid_object"][0].update(attrs={"mass": "heavy"}), "rigid_object[0].attrs.mass"),
        (lambda d: d["env"].update(seed="zero"), "env.seed"),
        (lambda d: d.update(max_episodes=0), "max_episodes"),
        (lambda d: d["env"].update(events=["tick"]), "env.events"),
        (lambda d: d["env"]["events"]["tick"].pop("func"), "env.events.tick.func"),
        (lambda d: d["env"].update(observations={"o": {"func": "g"}}), "env.observations.o.name"),
        (lambda d: d["rigid_object"][0].update(shape={"shape_type": "Mesh"}), "rigid_object[0].shape.fpath"),
    ],
)
def test_wrong_types_and_missing_values_name_the_path(mutate: Any, path: str) -> None:
    data = gym_config()
    mutate(data)
    assert config_error(data).path == path


@pytest.mark.parametrize("key", ["id", "robot", "env"])
def test_missing_required_keys(key: str) -> None:
    data = gym_config()
    del data[key]
    err = config_error(data)
    assert err.path == key
    assert "missing required key" in str(err)


def test_functor_name_typo_fails_at_env_construction_with_path(register_plugin: Any) -> None:
    class Functors:
        @hookimpl
        def embodichain_register_functors(self, register: Any) -> None:
            register("count_event", count_event, kind="event")

    register_plugin(Functors(), name="loader-test-functors")
    data = gym_config()
    data["env"]["events"]["tick"]["func"] = "count_evnt"
    _, cfg, _ = load_gym_config(data)  # names are resolved by the managers, not the loader
    with pytest.raises(ConfigError) as info:
        EmbodiedEnv(cfg)
    assert info.value.path == "env.events.tick.func"
    assert "Did you mean 'count_event'" in str(info.value)


def test_overrides_apply_only_when_given() -> None:
    _, cfg, extras = load_gym_config(gym_config(), {"num_envs": None, "seed": None, "max_episodes": None})
    assert (cfg.num_envs, cfg.seed, extras["max_episodes"]) == (2, 1, 3)
    overrides = {"num_envs": 4, "seed": 9, "max_episodes": 5, "headless": False, "renderer": "fast", "id": "X-v1"}
    task_id, cfg, extras = load_gym_config(gym_config(), overrides)
    assert (cfg.num_envs, cfg.sim_cfg.num_envs, cfg.seed, extras["max_episodes"]) == (4, 4, 9, 5)
    assert cfg.sim_cfg.headless is False
    assert cfg.sim_cfg.render_cfg.renderer == "fast"
    assert task_id == "X-v1"
    with pytest.raises(ConfigError, match="Did you mean 'num_envs'"):
        apply_overrides(cfg, extras, {"num_env": 2})


def test_file_errors_name_the_file(tmp_path: Path) -> None:
    (tmp_path / "list.yaml").write_text("- a\n- b\n")
    (tmp_path / "bad.json").write_text('{"id": ')
    for name, text in (
        ("list.yaml", "must be a mapping"),
        ("bad.json", "invalid JSON"),
        ("missing.json", "cannot read"),
        ("c.toml", "unsupported"),
    ):
        with pytest.raises(ConfigError, match=text) as info:
            load_config_file(tmp_path / name)
        assert str(tmp_path / name) in str(info.value)


def test_relative_model_paths_resolve_next_to_the_config(tmp_path: Path) -> None:
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "arm7.xml").write_text(seven_dof_arm_mjcf())
    data = gym_config(robot={"uid": "arm", "fpath": "models/arm7.xml"})
    (tmp_path / "c.json").write_text(json.dumps(data))
    _, cfg, _ = load_gym_config(tmp_path / "c.json")
    assert cfg.robot.fpath == str(tmp_path / "models" / "arm7.xml")
    env = EmbodiedEnv(cfg)
    try:
        assert env.robot.dof == 9
    finally:
        env.close()


def test_task_cfg_subclass_keeps_its_defaults() -> None:
    from embodichain_core.utils.configclass import configclass

    @configclass
    class TaskCfg(EmbodiedEnvCfg):
        max_episode_steps: int = 77
        sim_steps_per_control: int = 2

    cfg, _ = gym_config_to_cfg(_without(gym_config()), TaskCfg)
    assert isinstance(cfg, TaskCfg)
    assert cfg.max_episode_steps == 77
    assert cfg.sim_steps_per_control == 2


def test_the_documented_example_loads() -> None:
    text = (Path(__file__).parents[1] / "docs" / "configuration.md").read_text()
    example = json.loads(text.split("```json\n", 1)[1].split("```", 1)[0])
    task_id, cfg, extras = load_gym_config(example)
    assert task_id == "EmbodiChainDemo-v0"
    assert extras["max_episodes"] == 4
    assert cfg.sim_cfg.physics_dt == 0.005
    assert cfg.events["nudge"].is_global
    assert cfg.actions["delta_qpos"].mode == "pre"
    assert "robot_meta" in cfg.dataset
