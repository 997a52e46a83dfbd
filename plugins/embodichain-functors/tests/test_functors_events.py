"""Event functors: per-env mesh swaps, detached reset uids, group drops, settling,
rigid constraints, attribute and pose registration."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import CUBE_POS, apply, event, others, toy_ik_arm_cfg, write_box_obj, write_png

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers import EventCfg
from embodichain_core.managers import SceneEntityCfg as E
from embodichain_core.sim.cfg import RigidObjectCfg, RigidObjectGroupCfg
from embodichain_core.sim.shapes import CubeCfg, MeshCfg, VisualMaterialCfg

import embodichain_functors.events as events
import embodichain_functors.randomization as rand

IDS = [0, 3]


def _fork_folder(tmp_path) -> tuple[str, list[str]]:
    folder = tmp_path / "forks"
    folder.mkdir()
    files = [write_box_obj(str(folder / f"fork_{k}.obj"), (0.01 * (k + 1), 0.02, 0.01)) for k in range(3)]
    (folder / "fork_0.mtl").write_text("newmtl x\n")  # not a mesh: skipped
    write_png(str(folder / "preview.png"), (1, 2, 3))
    return str(folder), files


def _fork(files: list[str], **kwargs) -> RigidObjectCfg:
    shape = MeshCfg(fpath=files[0], visual_material=VisualMaterialCfg(base_color=(0.9, 0.1, 0.1, 1.0)))
    return RigidObjectCfg(uid="fork", shape=shape, init_pos=(0.3, -0.3, 0.02), **kwargs)


def test_replace_assets_gives_each_env_a_mesh_of_the_folder(build, tmp_path) -> None:
    folder, files = _fork_folder(tmp_path)
    env = build(
        rigid_object=[_fork(files)],
        events={
            "swap": EventCfg(
                func=events.replace_assets_from_group,
                mode="reset",
                params={"entity_cfg": E(uid="fork"), "folder_path": folder},
            )
        },
    )
    functor = env.event_manager.get_functor("swap")
    assert sorted(functor.files) == sorted(files)  # every mesh file, no .mtl / .png
    seen = set()
    for seed in range(6):
        env.reset(seed=seed)
        current = env.scene.current_mesh["fork"]
        assert len(current) == 4
        assert set(current) <= set(files)
        seen |= set(current)
        masses = env.scene["fork"].get_mass()
        for i, path in enumerate(current):  # each env simulates its mesh (mass ~ volume)
            assert masses[i] == pytest.approx(masses[[current.index(p) for p in current if p == path][0]])
    assert seen == set(files)


def test_replace_assets_only_touches_env_ids_and_keeps_the_material_colour(build, tmp_path) -> None:
    from embodichain_sensors.cfg import CameraCfg

    folder, files = _fork_folder(tmp_path)
    cam = CameraCfg(
        uid="cam",
        width=32,
        height=32,
        intrinsics=(40, 40, 16, 16),
        extrinsics=CameraCfg.ExtrinsicsCfg(eye=(0.3, -0.3, 0.3), target=(0.3, -0.3, 0.0)),
    )
    env = build(
        rigid_object=[_fork(files)],
        sensor=[cam],
        events=event(
            events.replace_assets_from_group, entity_cfg=E(uid="fork"), folder_path=str(tmp_path / "forks" / "*_2.obj")
        ),
    )
    apply(env, [1])
    current = env.scene.current_mesh["fork"]
    assert current[1] == files[2]
    assert current[0] == current[2] == current[3] == files[0]
    img = env.get_obs()["sensor"]["cam"]["color"][..., :3].float()
    centre = img[:, 14:18, 14:18].mean(dim=(1, 2))
    assert (centre[:, 0] > centre[:, 1] + 40).all()  # the red material shows on every variant


def test_replace_assets_bad_folder(build, tmp_path) -> None:
    _, files = _fork_folder(tmp_path)
    with pytest.raises(ConfigError, match="folder_path"):
        build(
            rigid_object=[_fork(files)],
            events=event(
                events.replace_assets_from_group, entity_cfg=E(uid="fork"), folder_path=str(tmp_path / "empty*")
            ),
        )


def test_detached_uids_are_added_once(build) -> None:
    env = build(
        events={
            "detach": EventCfg(func=events.set_detached_uids_for_env_reset, mode="startup", params={"uids": ["cube"]}),
            "detach2": EventCfg(func=events.set_detached_uids_for_env_reset, mode="reset", params={"uids": "cube"}),
        }
    )
    env.reset()
    env.reset()
    assert env._detached_uids_for_reset == ["cube"]


def test_detached_uids_skip_the_reset(build) -> None:
    env = build(
        events={
            "detach": EventCfg(func=events.set_detached_uids_for_env_reset, mode="startup", params={"uids": ["cube"]})
        }
    )
    env.reset()
    pose = env.scene["cube"].get_local_pose()
    pose[:, 0] += 0.2
    env.scene["cube"].set_local_pose(pose)
    env.reset()
    assert torch.allclose(env.scene["cube"].get_local_pose()[:, 0], torch.full((4,), CUBE_POS[0] + 0.2))


def test_drop_group_sequentially(build) -> None:
    group = RigidObjectGroupCfg(
        uid="blocks",
        rigid_objects={
            f"b{k}": RigidObjectCfg(shape=CubeCfg(size=[0.03] * 3), init_pos=(0.3, -0.6 - 0.1 * k, 0.015))
            for k in range(3)
        },
    )
    env = build(
        rigid_object_group=[group],
        events=event(
            events.drop_rigid_object_group_sequentially,
            entity_cfg=E(uid="blocks"),
            drop_position=[0.6, 0.3, 0.3],
            position_range=[[-0.02, -0.02, 0], [0.02, 0.02, 0]],
            physics_step=5,
        ),
    )
    before = env.scene["blocks"].get_local_pose()
    ids = apply(env, IDS)
    pose = env.scene["blocks"].get_local_pose()
    assert ((pose[ids, :, 0] - 0.6).abs() < 0.05).all()
    assert ((pose[ids, :, 1] - 0.3).abs() < 0.05).all()
    assert (pose[ids, 0, 2] < pose[ids, 2, 2]).all()  # the first one fell longest
    assert torch.equal(pose[others(IDS)], before[others(IDS)])


def test_settle_steps_only_chosen_envs_until_rest(build) -> None:
    env = build(
        events={
            "lift": EventCfg(
                func=rand.randomize_rigid_object_pose,
                mode="test",
                params={"entity_cfg": E(uid="cube"), "position_range": [[0, 0, 0.2], [0, 0, 0.2]]},
            ),
            "settle": EventCfg(func=events.wait_for_dynamic_objects_to_settle, mode="test", params={"max_steps": 400}),
        }
    )
    ball0 = env.scene["ball"].get_local_pose()
    ids = apply(env, IDS)
    cube = env.scene["cube"].get_local_pose()
    assert torch.allclose(cube[ids, 2], torch.full((2,), 0.025), atol=2e-3)  # landed
    assert torch.allclose(cube[others(IDS), 2], torch.full((2,), 0.025))  # never lifted, never stepped
    assert env.scene["cube"].get_velocity()[ids].norm(dim=-1).max() < 0.03
    assert torch.equal(env.scene["ball"].get_local_pose()[others(IDS)], ball0[others(IDS)])


def test_settle_timeout_warns_or_raises(build) -> None:
    params = {"entity_cfgs": [E(uid="cube")], "min_steps": 0, "max_steps": 2, "check_interval_steps": 1}
    env = build(
        events={
            "lift": EventCfg(
                func=rand.randomize_rigid_object_pose,
                mode="test",
                params={"entity_cfg": E(uid="cube"), "position_range": [[0, 0, 1], [0, 0, 1]]},
            ),
            "settle": EventCfg(func=events.wait_for_dynamic_objects_to_settle, mode="test", params=params),
        }
    )
    with pytest.warns(RuntimeWarning, match="still moving"):
        apply(env, IDS)
    env = build(
        events=event(
            events.wait_for_dynamic_objects_to_settle,
            **params,
            timeout_behavior="raise",
            linear_velocity_threshold=1e-12,
            angular_velocity_threshold=1e-12,
        )
    )
    env.scene["cube"].set_velocity(torch.ones(4, 6))
    with pytest.raises(RuntimeError, match="still moving"):
        apply(env, IDS)


@pytest.mark.parametrize(
    "params, param",
    [
        ({"entity_cfgs": [E(uid="table")]}, "entity_cfgs"),
        ({"entity_cfgs": [E(uid="arm")]}, "entity_cfgs"),
        ({"min_steps": 50, "max_steps": 10}, "min_steps"),
        ({"timeout_behavior": "ignore"}, "timeout_behavior"),
    ],
)
def test_settle_bad_params(build, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(events.wait_for_dynamic_objects_to_settle, **params)), IDS)
    assert err.value.path == f"env.events.ev.params.{param}"


def test_settle_rejects_partial_envs_when_asked(build) -> None:
    env = build(events=event(events.wait_for_dynamic_objects_to_settle, allow_partial_envs=False))
    with pytest.raises(ValueError, match="allow_partial_envs"):
        apply(env, IDS)


def _ball_in_cube(env) -> torch.Tensor:
    """(N, 3) ball position in the cube's frame."""
    from embodichain_core.utils.math import quat_conjugate, quat_rotate

    cube, ball = env.scene["cube"].get_local_pose(), env.scene["ball"].get_local_pose()
    return quat_rotate(quat_conjugate(cube[:, 3:]), ball[:, :3] - cube[:, :3])


def _weld_events(**params) -> dict:
    return {
        "attach": EventCfg(
            func=events.create_rigid_constraint,
            mode="attach",
            params={"obj_a_cfg": E(uid="cube"), "obj_b_cfg": E(uid="ball"), "name": "w", **params},
        ),
        "detach": EventCfg(func=events.remove_rigid_constraint, mode="detach", params={"name": "w"}),
    }


def test_weld_holds_relative_pose_in_chosen_envs_until_removed(build) -> None:
    env = build(events=_weld_events())
    env.reset()
    rel0 = _ball_in_cube(env)
    apply(env, [1], mode="attach")
    env.scene["ball"].set_velocity(torch.tensor([[0.0, 0.0, 2.0, 0, 0, 0]]).expand(4, 6))
    for _ in range(5):
        env.step(torch.zeros(env.action_space.shape))
    moved = (_ball_in_cube(env) - rel0).norm(dim=-1)
    assert moved[1] < 5e-3
    assert (moved[[0, 2, 3]] > 0.03).all()
    assert env.scene["cube"].get_local_pose()[1, 2] > 0.03  # lifted along with the ball
    apply(env, [1], mode="detach")
    apply(env, [1], mode="detach")  # idempotent
    assert env.sim.eq_active[1, -1] == 0


def test_weld_with_local_frames_and_reset_clears_it(build) -> None:
    env = build(events=_weld_events(local_frame_a=[0, 0, 0.1, 1, 0, 0, 0], local_frame_b=[0, 0, 0, 1, 0, 0, 0]))
    env.reset()
    apply(env, [2], mode="attach")
    for _ in range(40):
        env.step(torch.zeros(env.action_space.shape))
    assert torch.allclose(_ball_in_cube(env)[2], torch.tensor([0.0, 0.0, 0.1]), atol=5e-3)
    assert torch.allclose(_ball_in_cube(env)[1], torch.tensor([-0.1, 0.25, 0.005]), atol=1e-3)  # not welded
    env.reset(options={"reset_ids": [2]})
    assert env.sim.eq_active[2, -1] == 0


def test_constraint_bad_params(build) -> None:
    with pytest.raises(ConfigError, match="obj_b_cfg"):
        build(
            events={
                "attach": EventCfg(
                    func=events.create_rigid_constraint,
                    mode="attach",
                    params={"obj_a_cfg": E(uid="cube"), "obj_b_cfg": E(uid="arm"), "name": "w"},
                )
            }
        )
    with pytest.raises(ConfigError) as err:
        apply(build(events=event(events.remove_rigid_constraint, name="nope")), IDS)
    assert err.value.path == "env.events.ev.params.name"


def test_prepare_and_register_attributes_and_poses(build) -> None:
    grasp = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.02], [0, 0, 0, 1]]
    env = build(
        robot=toy_ik_arm_cfg(),
        events={
            "prep": EventCfg(
                func=events.prepare_extra_attr,
                mode="reset",
                params={
                    "attrs": [
                        {"name": "grasp_pose_object", "entity_uids": "cube", "mode": "static", "value": grasp},
                        {
                            "name": "hand_pose",
                            "entity_cfg": E(uid="arm"),
                            "mode": "callable",
                            "func_name": "get_link_pose",
                            "func_kwargs": {"link_name": "hand"},
                        },
                    ]
                },
            ),
            "reg": EventCfg(
                func=events.register_info_to_env,
                mode="reset",
                params={
                    "registry": [
                        {
                            "entity_cfg": E(uid="cube"),
                            "attrs": ["grasp_pose_object", "body_scale"],
                            "pose_register_params": {"compute_relative": ["ball"]},
                        },
                        {"entity_cfg": E(uid="arm", control_parts=["arm"]), "attrs": ["hand_pose"], "prefix": False},
                    ]
                },
            ),
        },
    )
    env.reset()
    data = env.affordance_datas
    assert data["cube_pose"].shape == (4, 4, 4)
    assert torch.allclose(data["cube_pose"][:, :3, 3], torch.tensor(CUBE_POS).expand(4, 3))
    assert torch.allclose(
        data["ball_pose_in_cube"][:, :3, 3], torch.tensor([-0.1, 0.25, 0.005]).expand(4, 3), atol=1e-5
    )
    assert torch.allclose(data["cube_grasp_pose"][:, 2, 3], torch.full((4,), CUBE_POS[2] + 0.02))
    assert data["cube_body_scale"].shape == (4, 3)
    assert data["hand_pose"].shape == (4, 7)
    assert data["arm_pose"].shape == (4, 4, 4)
    assert events.resolve_uids(env, "all_objects") == ["cube", "ball"]
    assert events.resolve_uids(env, "all_robots") == ["arm"]
    assert events.resolve_uids(env, ["cube"]) == ["cube"]
    assert list(events.resolve_dict(env, {"all_objects": {"k": 1}})) == ["cube", "ball"]


def test_registration_bad_params(build) -> None:
    with pytest.raises(ConfigError, match="mode"):
        build(events=event(events.prepare_extra_attr, attrs=[{"name": "x", "entity_uids": "cube", "mode": "magic"}]))
    with pytest.raises(ConfigError) as err:
        apply(
            build(
                events=event(
                    events.register_entity_attrs, entity_cfg={"uid": "cube"}, attrs=["x"], registration="not valid"
                )
            ),
            IDS,
        )
    assert err.value.path == "env.events.ev.params.registration"
