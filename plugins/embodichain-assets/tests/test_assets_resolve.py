"""Every asset the seed tutorial (and the pack) names resolves through the plugin and loads."""

from __future__ import annotations

import os

import numpy as np
import pytest

from embodichain_assets import DATA_ROOT, catalog
from embodichain_assets.pngread import read_png
from embodichain_core.sim.data import DataPathNotFoundError, data_roots, get_data_path
from embodichain_core.sim.scene_build.mesh import MESH_SUFFIXES, is_closed, is_convex, load_mesh, split_components

# the names exactly as the seed tutorial (modular_env.py) writes them
SEED_TUTORIAL_NAMES = [
    "CircleTableSimple/circle_table_simple.ply",
    "TableWare/tableware/fork/",
    "TableWare/tableware/fork/standard_fork_scale.ply",
    "CocoBackground/coco",
    "SlidingBoxDrawer/SlidingBoxDrawer.urdf",
]
PACK_NAMES = [a.name for a in catalog.MESHES] + [catalog.DRAWER, catalog.COCO_FOLDER]


def test_plugin_registers_the_data_root():
    assert str(DATA_ROOT) in data_roots()


def test_entry_point_registers_one_asset_root(register_plugin, plugin_manager):
    from importlib.metadata import entry_points

    import embodichain_assets.plugin

    (entry,) = [e for e in entry_points(group="embodichain") if e.name == "embodichain-assets"]
    assert entry.value == "embodichain_assets.plugin"
    register_plugin(embodichain_assets.plugin)
    assert plugin_manager.registry("assets").names() == ["embodichain-assets"]


@pytest.mark.parametrize("name", SEED_TUTORIAL_NAMES + PACK_NAMES)
def test_every_name_resolves_into_the_pack(name):
    path = get_data_path(name)
    assert os.path.exists(path)
    assert os.path.realpath(path).startswith(os.path.realpath(DATA_ROOT))
    assert path.endswith("/") == name.endswith("/")  # a folder name keeps its trailing slash


def test_fork_folder_holds_only_fork_meshes():
    folder = get_data_path("TableWare/tableware/fork/")
    files = sorted(os.listdir(folder))
    assert "standard_fork_scale.ply" in files
    assert len(files) >= 5
    assert all(os.path.splitext(f)[1] in MESH_SUFFIXES for f in files), files  # the replace functor takes every file
    for name in files:
        lo, hi = load_mesh(os.path.join(folder, name)).bounds
        length, width, thickness = hi - lo
        assert 0.13 <= length <= 0.22, (name, hi - lo)
        assert 0.02 <= width <= 0.031, (name, hi - lo)
        assert thickness <= 0.021, (name, hi - lo)
        np.testing.assert_allclose((lo + hi) / 2.0, 0.0, atol=1e-6)  # origin at the bbox centre


def test_coco_folder_holds_32_png_textures_that_mujoco_decodes():
    folder = get_data_path("CocoBackground/coco")
    files = sorted(f for f in os.listdir(folder) if f.lower().endswith((".png", ".jpg", ".jpeg")))
    assert len(files) >= 32
    means = []
    for name in files:
        with open(os.path.join(folder, name), "rb") as handle:
            pixels = read_png(handle.read())
        assert pixels.shape == (256, 256, 3)
        means.append(pixels.reshape(-1, 3).mean(axis=0))
    assert len({tuple(np.round(m, 1)) for m in means}) == len(files)  # all different images


@pytest.mark.parametrize("asset", catalog.MESHES, ids=lambda a: a.name)
def test_meshes_are_unions_of_closed_convex_parts(asset):
    mesh = load_mesh(get_data_path(asset.name))
    parts = split_components(mesh)
    assert all(is_closed(p) for p in parts)
    convex = [is_convex(p) for p in parts]
    if asset.convex_parts:
        assert all(convex), asset.name
    else:  # the mug: convex body + deliberately non-convex handle
        assert asset.name == catalog.MUG
        assert convex == [True, False]


def test_table_and_object_dimensions():
    table = load_mesh(get_data_path(catalog.CIRCLE_TABLE))
    lo, hi = table.bounds
    np.testing.assert_allclose(lo, [-0.02, -0.45, -0.45], atol=1e-6)  # top surface at mesh x = -0.02
    np.testing.assert_allclose(hi, [0.80, 0.45, 0.45], atol=1e-6)  # the base reaches 0.80 below the slab centre
    lo, hi = load_mesh(get_data_path(catalog.SHOP_TABLE)).bounds
    np.testing.assert_allclose([lo, hi], [[-0.3, -0.25, 0.0], [0.3, 0.25, 0.8]], atol=1e-6)
    lo, hi = load_mesh(get_data_path(catalog.SODA_CAN)).bounds
    np.testing.assert_allclose([lo, hi], [[-0.033, -0.033, 0.0], [0.033, 0.033, 0.122]], atol=1e-5)


def test_drawer_urdf_keeps_links_and_joint_range():
    from embodichain_core.sim.scene_build.articulation_loader import joint_dynamics, list_joints, load_articulation_spec

    spec = load_articulation_spec(get_data_path(catalog.DRAWER))
    assert [b.name for b in spec.bodies] == ["world", "outer_box", "inner_drawer", "handle_xpos"]
    (joint,) = list_joints(spec)
    assert (joint.name, joint.type, joint.range) == ("slide_rails", "slide", (0.0, 0.2))
    assert joint_dynamics(spec)["slide_rails"]["damping"] == pytest.approx(1.0)
    with open(get_data_path(catalog.DRAWER), encoding="utf-8") as handle:
        assert '<compiler fusestatic="false" discardvisual="false"/>' in handle.read()
    spec.compile()


def test_missing_name_lists_roots_and_closest_names():
    with pytest.raises(DataPathNotFoundError) as info:
        get_data_path("CircleTableSimpel/circle_table_simple.ply")
    message = str(info.value)
    assert str(DATA_ROOT) in message
    assert "Searched roots:" in message
    assert "'CircleTableSimple/circle_table_simple.ply'" in message
    with pytest.raises(DataPathNotFoundError) as info:
        get_data_path("TableWare/tableware/fork/standard_fork.ply")
    # the core suggests names up to three levels deep: here the fork folder, not the file in it
    assert "'TableWare/tableware/fork/'" in str(info.value)
