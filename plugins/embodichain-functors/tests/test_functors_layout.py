"""Layout randomization (class functors): distinct grid cells; anchor height shifts."""

from __future__ import annotations

import pytest
import torch
from functors_testlib import TABLE_POS, apply, event, others

from embodichain_core.config.errors import ConfigError
from embodichain_core.sim.cfg import ArticulationCfg

import embodichain_functors.randomization as rand

IDS = [1, 2]
GRID = dict(
    position_range=[[0.2, -0.3], [0.8, 0.3]], reference_height=0.1, object_uid_list=["cube", "ball"], grid_size=[2, 1]
)


def test_grid_cells_are_distinct_cell_centres(build) -> None:
    env = build(events=event(rand.planner_grid_cell_sampler, **GRID))
    before = env.scene["cube"].get_local_pose()
    ids = apply(env, IDS)
    cube, ball = env.scene["cube"].get_local_pose(), env.scene["ball"].get_local_pose()
    centres = {(0.35, 0.0), (0.65, 0.0)}  # two cells of 0.3 x 0.6
    for i in ids.tolist():
        a, b = tuple(round(v, 4) for v in cube[i, :2].tolist()), tuple(round(v, 4) for v in ball[i, :2].tolist())
        assert {a, b} == centres
    assert torch.allclose(cube[ids, 2], torch.full((2,), 0.1))
    assert torch.equal(cube[others(IDS)], before[others(IDS)])


def test_grid_draws_differ_between_envs(build) -> None:
    env = build(events=event(rand.planner_grid_cell_sampler, **{**GRID, "grid_size": [4, 4]}))
    apply(env, [0, 1, 2, 3])
    cells = {tuple(p) for p in env.scene["cube"].get_local_pose()[:, :2].tolist()}
    assert len(cells) > 1


def test_grid_rejects_too_few_cells(build) -> None:
    with pytest.raises(ConfigError) as err:
        build(events=event(rand.planner_grid_cell_sampler, **{**GRID, "grid_size": [1, 1]}))
    assert err.value.path == "env.events.ev"
    assert "planner_grid_cell_sampler" in str(err.value)
    assert "params.grid_size" in str(err.value)


def _drawer() -> ArticulationCfg:
    return ArticulationCfg(
        uid="shelf",
        init_pos=(-0.5, 0.0, 0.0),
        mjcf=(
            '<mujoco><worldbody><body name="base"><geom type="box" size=".05 .05 .05"/>'
            '<body name="door" pos="0 0 .06"><joint name="hinge" axis="1 0 0"/><geom type="box" size=".05 .05 .01"/>'
            "</body></body></worldbody></mujoco>"
        ),
    )


def test_anchor_height_moves_anchor_and_everything_on_it(build) -> None:
    env = build(
        articulation=[_drawer()],
        events=event(
            rand.randomize_anchor_height, anchor_uid="table", height_delta_range=[0.05, 0.1], exclude_uids=["cube"]
        ),
    )
    poses = lambda uid: env.scene[uid].get_local_pose().clone()  # noqa: E731
    table0, ball0, cube0, shelf0 = poses("table"), poses("ball"), poses("cube"), poses("shelf")
    ids = apply(env, IDS)
    apply(env, IDS)  # again: the anchor is absolute, the fixed-base articulation does not drift
    dz = env.anchor_height_delta
    assert ((dz[ids] >= 0.05) & (dz[ids] <= 0.1)).all()
    assert (dz[others(IDS)] == 0).all()
    table, ball, shelf = poses("table"), poses("ball"), poses("shelf")
    assert torch.allclose(table[ids, 2], TABLE_POS[2] + dz[ids])
    assert torch.allclose(shelf[ids, 2], shelf0[ids, 2] + dz[ids], atol=1e-6)
    assert torch.allclose(table[ids, :2], table0[ids, :2])
    assert torch.allclose(table[ids, 3:], table0[ids, 3:])
    assert (ball[ids, 2] > ball0[ids, 2] + 0.1 - 1e-6).all()  # moved twice (>= 0.05 each), relative to its z
    assert torch.equal(ball[others(IDS)], ball0[others(IDS)])
    assert torch.equal(poses("cube"), cube0)  # excluded
    assert torch.equal(table[others(IDS)], table0[others(IDS)])


def test_floating_anchor_is_placed_from_its_edited_init_root_pose(build) -> None:
    """A floating-base anchor's height is its ``init_root_pose``'s (edited in place) plus the draw."""
    box = ArticulationCfg(
        uid="box",
        fix_base=False,
        init_pos=(0.0, -0.5, 0.1),
        mjcf='<mujoco><worldbody><body name="base"><geom type="box" size=".05 .05 .05" mass="1"/></body></worldbody></mujoco>',
    )
    env = build(
        articulation=[box],
        events=event(rand.randomize_anchor_height, anchor_uid="box", height_delta_candidates=[0.2], include_groups=[]),
    )
    env.scene["box"].init_root_pose[2] = 0.4
    ids = apply(env, IDS)
    assert torch.allclose(env.scene["box"].get_local_pose()[ids, 2], torch.full((2,), 0.6), atol=1e-5)


def test_anchor_height_candidates(build) -> None:
    env = build(events=event(rand.randomize_anchor_height, anchor_uid="table", height_delta_candidates=[-0.1, 0.2]))
    apply(env, [0, 1, 2, 3])
    assert all(min(abs(v - c) for c in (-0.1, 0.2)) < 1e-6 for v in env.anchor_height_delta.tolist())


@pytest.mark.parametrize(
    "params, param",
    [
        ({"anchor_uid": "nope", "height_delta_range": [0, 1]}, "anchor_uid"),
        ({"anchor_uid": "table"}, "height_delta_range"),
        ({"anchor_uid": "table", "height_delta_candidates": []}, "height_delta_candidates"),
        ({"anchor_uid": "table", "height_delta_range": [0, 1], "include_groups": ["robots"]}, "include_groups"),
    ],
)
def test_anchor_height_bad_params(build, params, param) -> None:
    with pytest.raises(ConfigError) as err:
        build(events=event(rand.randomize_anchor_height, **params))
    assert f"params.{param}" in str(err.value)
    assert "randomize_anchor_height" in str(err.value)
