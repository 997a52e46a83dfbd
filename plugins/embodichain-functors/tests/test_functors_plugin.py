"""The plugin: registration through the entry point, documentation of every functor,
the generated catalogue, JSON configs naming functors, per-env reproducible draws."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
from pathlib import Path

import numpy as np
import pytest
import torch
from functors_testlib import N

from embodichain_core.config.loader import gym_config_to_cfg
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.plugins import functor_registry, is_visual_randomization
from embodichain_core.plugins.registry import first_doc_line

from embodichain_functors.catalogue import FUNCTORS

PLUGIN = Path(__file__).resolve().parents[1]
REPO = PLUGIN.parents[1]


def _gen_catalogue():
    spec = importlib.util.spec_from_file_location("gen_catalogue", PLUGIN / "scripts" / "gen_catalogue.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_functor_is_registered_by_the_entry_point() -> None:
    registry = functor_registry()
    for name, target, kind, category, description in FUNCTORS:
        entry = registry.entry(name)
        assert entry.provider == "embodichain-functors"
        assert entry.target == target
        assert entry.meta["kind"] == kind
        assert entry.meta["category"] == category
        assert description == first_doc_line(entry.resolve()), f"{name}: description drifted from the docstring"


def test_modules_import_like_the_seed_tutorial() -> None:
    import embodichain_functors.events as events
    import embodichain_functors.observations as obs
    import embodichain_functors.randomization as rand

    assert callable(rand.randomize_light)
    assert inspect.isclass(events.replace_assets_from_group)
    assert callable(rand.randomize_rigid_object_mass)
    assert inspect.isclass(rand.randomize_visual_material)
    assert callable(obs.get_rigid_object_pose)


@pytest.mark.parametrize("name", [row[0] for row in FUNCTORS])
def test_every_functor_documents_params_and_an_example(name) -> None:
    obj = functor_registry().get(name)
    doc = inspect.getdoc(obj) or ""
    assert "Example:" in doc, f"{name}: no example config entry"
    assert '"func"' in doc, f"{name}: no example config entry"
    params = _gen_catalogue().params_of(obj, functor_registry().entry(name).meta["kind"])
    for param in (p.split("=")[0] for p in params):
        assert param in doc, f"{name}: param {param!r} is not documented"


def test_committed_catalogue_matches_the_registry() -> None:
    committed = (REPO / "docs" / "functor_catalogue.md").read_text()
    assert committed == _gen_catalogue().render(), "run plugins/embodichain-functors/scripts/gen_catalogue.py"


def test_visual_randomization_names() -> None:
    visual = {row[0] for row in FUNCTORS if row[0].startswith("randomize_") and row[3] == "randomization.visual"}
    assert visual == {
        "randomize_light",
        "randomize_visual_material",
        "randomize_camera_extrinsics",
        "randomize_camera_intrinsics",
    }
    assert all(is_visual_randomization(n) for n in visual)
    assert not is_visual_randomization("set_rigid_object_visual_material")
    assert not is_visual_randomization("randomize_rigid_object_mass")


def test_functors_declare_the_visual_category_they_are_registered_with() -> None:
    """A functor named by import path is filtered by ``filter_visual_rand`` through its own
    ``embodichain_category``: it says what its registration says."""
    for name, target, _kind, category, _description in FUNCTORS:
        module, _, attr = target.partition(":")
        declared = getattr(getattr(importlib.import_module(module), attr), "embodichain_category", None)
        if name.startswith("randomize_") and category == "randomization.visual":
            assert declared == category, f"{name} does not declare embodichain_category = {category!r}"
        else:
            assert declared in (None, category), f"{name} declares {declared!r}, registered as {category!r}"


GYM_CONFIG = {
    "id": "FunctorsJsonTest-v0",
    "num_envs": N,
    "env": {
        "seed": 7,
        "control_parts": ["arm"],
        "events": {
            "mass": {
                "func": "randomize_rigid_object_mass",
                "mode": "reset",
                "params": {"entity_cfg": {"uid": "cube"}, "mass_range": [0.5, 2.0]},
            },
            "pose": {
                "func": "randomize_rigid_object_pose",
                "mode": "reset",
                "params": {"entity_cfg": {"uid": "cube"}, "position_range": [[-0.1, -0.1, 0], [0.1, 0.1, 0]]},
            },
            "light": {
                "func": "randomize_light",
                "mode": "interval",
                "interval_step": 2,
                "params": {"entity_cfg": {"uid": "point"}, "intensity_range": [-5, 5]},
            },
            "mat": {
                "func": "randomize_visual_material",
                "mode": "reset",
                "params": {"entity_cfg": {"uid": "table"}, "base_color_range": [[0, 0, 0], [1, 1, 1]]},
            },
            "goal": {
                "func": "randomize_target_pose",
                "mode": "reset",
                "params": {"position_range": [[0.3, -0.2, 0.05], [0.6, 0.2, 0.05]], "store_key": "goal_pose"},
            },
        },
        "observations": {
            "cube": {
                "func": "get_rigid_object_pose",
                "mode": "add",
                "name": "object/cube",
                "params": {"entity_cfg": {"uid": "cube"}, "to_matrix": False},
            },
            "norm": {"func": "normalize_robot_joint_data", "mode": "modify", "name": "robot/qpos"},
            "goal": {"func": "target_position", "mode": "add", "name": "task/goal"},
        },
        "rewards": {
            "dist": {
                "func": "distance_to_target",
                "weight": 0.5,
                "params": {"source_entity_cfg": {"uid": "cube"}, "target_pose_key": "goal_pose"},
            },
            "smooth": {"func": "action_smoothness_penalty", "weight": 0.01},
        },
        "actions": {"arm": {"func": "DeltaQposTerm", "params": {"scale": 0.1}}},
    },
    "robot": {
        "uid": "arm",
        "fpath": str(Path(importlib.util.find_spec("embodichain_core").origin).parent / "demo" / "arm7.xml"),
        "control_parts": {"arm": ["joint[1-7]"]},
    },
    "light": {"direct": [{"uid": "point", "init_pos": [0, 0, 2]}]},
    "background": [
        {
            "uid": "table",
            "shape": {"shape_type": "Cube", "size": [0.4, 0.4, 0.4]},
            "body_type": "kinematic",
            "init_pos": [0, 0.8, 0.2],
        }
    ],
    "rigid_object": [
        {"uid": "cube", "shape": {"shape_type": "Cube", "size": [0.05, 0.05, 0.05]}, "init_pos": [0.5, 0, 0.025]}
    ],
}


def _state(env: EmbodiedEnv) -> list[np.ndarray]:
    cube = env.scene["cube"]
    return [
        np.array(env.sim.model_field("body_mass")[:, cube.body_id]),
        cube.get_local_pose().numpy(),
        np.array(env.sim.model_field("mat_rgba")),
        env.goal_pose.numpy(),
    ]


def test_a_json_config_names_functors_and_draws_are_per_env_and_reproducible() -> None:
    envs = []
    try:
        for _ in range(2):
            cfg, _ = gym_config_to_cfg(GYM_CONFIG)
            cfg.verbose = False
            envs.append(EmbodiedEnv(cfg))
            envs[-1].reset()
        a, b = (_state(e) for e in envs)
        assert all(np.array_equal(x, y) for x, y in zip(a, b))  # same seed, same draws
        assert len(set(a[0].tolist())) == N
        assert len({tuple(p) for p in a[1][:, :2].tolist()}) == N
        obs, reward, *_ = envs[0].step(torch.zeros(envs[0].action_space.shape))
        assert obs["object"]["cube"].shape == (N, 7)
        assert reward.shape == (N,)
        envs[0].reset(seed=8)
        assert not np.array_equal(_state(envs[0])[0], a[0])  # another seed, other draws
    finally:
        for env in envs:
            env.close()
