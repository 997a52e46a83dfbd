"""URDF/MJCF -> MjSpec: fixed links kept, limits and dynamics, foreign meshes, attaching."""

from __future__ import annotations

import os

import mujoco
import numpy as np
import pytest
import trimesh

from embodichain_core.sim.scene_build.articulation_loader import (
    JointInfo,
    joint_dynamics,
    list_joints,
    load_articulation_spec,
    prepare_urdf,
    resolve_mesh_path,
    urdf_mesh_files,
)

INERTIAL = '<inertial><mass value="{m}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'


def drawer_urdf(outer_geometry: str = '<box size="0.4 0.36 0.01"/>', extra: str = "") -> str:
    """A SlidingBoxDrawer-like URDF: outer box, prismatic drawer, fixed handle frame."""
    return f"""<?xml version="1.0"?>
<robot name="drawer">
  <link name="outer_box">{INERTIAL.format(m=3)}
    <visual><geometry>{outer_geometry}</geometry></visual>
    <collision><geometry>{outer_geometry}</geometry></collision>
  </link>
  <link name="inner_drawer">{INERTIAL.format(m=0.5)}
    <collision><geometry><box size="0.36 0.32 0.01"/></geometry></collision>
  </link>
  <link name="handle_xpos"/>
  <joint name="slide_rails" type="prismatic">
    <parent link="outer_box"/><child link="inner_drawer"/>
    <origin xyz="0 0 0.02"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.2" effort="50" velocity="1"/>
    <dynamics damping="1.0" friction="0.05"/>
  </joint>
  <joint name="handle_joint" type="fixed">
    <parent link="inner_drawer"/><child link="handle_xpos"/>
    <origin xyz="0.2 0 0.08" rpy="0 -1.5707963 0"/>
  </joint>
  {extra}
</robot>"""


def write(path, text: str) -> str:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as handle:
        handle.write(text)
    return str(path)


def test_fixed_link_kept_and_joint_limits(tmp_path):
    spec = load_articulation_spec(write(tmp_path / "drawer.urdf", drawer_urdf()))
    assert [b.name for b in spec.bodies] == ["world", "outer_box", "inner_drawer", "handle_xpos"]
    assert list_joints(spec) == [JointInfo("slide_rails", "slide", (0.0, 0.2))]
    dyn = joint_dynamics(spec)["slide_rails"]
    assert dyn["damping"] == pytest.approx(1.0)
    assert dyn["frictionloss"] == pytest.approx(0.05)
    assert dyn["actfrcrange"] == (-50.0, 50.0)
    model = spec.compile()
    handle = model.body("handle_xpos")
    assert model.jnt_limited[0]
    assert model.jnt_range[0].tolist() == [0.0, 0.2]
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    z_axis = data.xmat[handle.id].reshape(3, 3)[:, 2]
    np.testing.assert_allclose(z_axis, [-1.0, 0.0, 0.0], atol=1e-6)  # +Z points into the drawer


def test_visual_geoms_are_kept_and_do_not_collide(tmp_path):
    spec = load_articulation_spec(write(tmp_path / "drawer.urdf", drawer_urdf()))
    model = spec.compile()
    body = model.body("outer_box").id
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body]
    assert sorted(int(model.geom_contype[g]) for g in geoms) == [0, 1]


def test_existing_compiler_block_is_completed_not_overridden():
    text = drawer_urdf().replace(
        '<robot name="drawer">', '<robot name="drawer"><mujoco><compiler discardvisual="true"/></mujoco>'
    )
    out = prepare_urdf(text, "/tmp")
    assert 'discardvisual="true"' in out
    assert 'fusestatic="false"' in out
    assert 'strippath="false"' in out
    assert out.count("<mujoco>") == 1


def test_attach_with_prefix_compiles_from_another_cwd(tmp_path, monkeypatch):
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box((0.4, 0.36, 0.01)).export(tmp_path / "meshes" / "outer.stl")
    urdf = write(tmp_path / "d" / "drawer.urdf", drawer_urdf('<mesh filename="../meshes/outer.stl"/>'))
    monkeypatch.chdir("/")
    for mode in ("attach_body", "attach"):
        child = load_articulation_spec(urdf)
        scene = mujoco.MjSpec()
        frame = scene.worldbody.add_frame(pos=[0.5, 0.0, 0.85])
        if mode == "attach_body":
            frame.attach_body(child.worldbody.first_body(), "drawer/", "")
        else:
            scene.attach(child, frame=frame, prefix="drawer/")
        model = scene.compile()
        assert model.body("drawer/handle_xpos").id > 0
        assert model.joint("drawer/slide_rails").range.tolist() == [0.0, 0.2]
        assert model.nmesh == 1  # the importer shares one mesh between visual and collision
    again = mujoco.MjSpec.from_string(scene.to_xml())  # absolute paths survive a round trip
    assert again.compile().nmesh == 1


def test_ply_meshes_are_injected_as_user_vertices(tmp_path):
    trimesh.creation.box((0.2, 0.2, 0.2)).export(tmp_path / "outer.ply")
    geometry = '<mesh filename="outer.ply" scale="2 1 1"/>'
    spec = load_articulation_spec(write(tmp_path / "drawer.urdf", drawer_urdf(geometry)))
    assert spec.meshes
    assert all(m.file == "" and len(m.uservert) > 0 for m in spec.meshes)
    model = spec.compile()
    mesh = model.mesh_vert[model.mesh_vertadr[0] : model.mesh_vertadr[0] + model.mesh_vertnum[0]]
    assert np.ptp(mesh, axis=0).max() == pytest.approx(0.4, rel=1e-5)  # URDF scale still applies


def test_package_paths_are_searched_upward(tmp_path):
    pkg = tmp_path / "my_pkg"
    (pkg / "meshes").mkdir(parents=True)
    trimesh.creation.box((0.1, 0.1, 0.1)).export(pkg / "meshes" / "outer.stl")
    geometry = '<mesh filename="package://my_pkg/meshes/outer.stl"/>'
    urdf = write(pkg / "urdf" / "drawer.urdf", drawer_urdf(geometry))
    assert urdf_mesh_files(urdf) == [str(pkg / "meshes" / "outer.stl")]
    assert load_articulation_spec(urdf).compile().nmesh == 1
    with pytest.raises(FileNotFoundError, match="tried"):
        resolve_mesh_path("package://my_pkg/meshes/missing.stl", str(pkg / "urdf"))


def test_continuous_and_revolute_joints_in_order(tmp_path):
    extra = f"""
  <link name="knob">{INERTIAL.format(m=0.1)}</link>
  <link name="flap">{INERTIAL.format(m=0.1)}</link>
  <joint name="knob_joint" type="continuous"><parent link="inner_drawer"/><child link="knob"/>
    <axis xyz="1 0 0"/></joint>
  <joint name="flap_joint" type="revolute"><parent link="outer_box"/><child link="flap"/>
    <axis xyz="0 1 0"/><limit lower="-0.5" upper="1.0" effort="1" velocity="1"/></joint>"""
    spec = load_articulation_spec(write(tmp_path / "drawer.urdf", drawer_urdf(extra=extra)))
    joints = {j.name: j for j in list_joints(spec)}
    assert joints["knob_joint"] == JointInfo("knob_joint", "hinge", None)
    assert joints["flap_joint"].range == (-0.5, 1.0)
    assert [j.name for j in list_joints(spec)] == [j.name for j in spec.joints]


def test_mjcf_meshdir_resolved_and_attachable(tmp_path, monkeypatch):
    (tmp_path / "assets").mkdir()
    trimesh.creation.box((0.1, 0.1, 0.1)).export(tmp_path / "assets" / "b.obj")
    trimesh.creation.box((0.1, 0.1, 0.1)).export(tmp_path / "assets" / "c.ply")
    xml = """<mujoco><compiler meshdir="assets"/>
      <asset><mesh file="b.obj"/><mesh file="c.ply"/></asset>
      <worldbody><body name="lid"><joint name="hinge" range="0 1.5"/>
        <geom type="mesh" mesh="b"/><geom type="mesh" mesh="c"/></body></worldbody></mujoco>"""
    path = write(tmp_path / "box.xml", xml)
    monkeypatch.chdir("/")
    spec = load_articulation_spec(path)
    assert spec.meshes[0].file == str(tmp_path / "assets" / "b.obj")
    assert spec.meshes[1].file == ""  # PLY is injected as user vertices
    assert list_joints(spec) == [JointInfo("hinge", "hinge", (0.0, 1.5))]
    scene = mujoco.MjSpec()
    scene.worldbody.add_frame().attach_body(spec.worldbody.first_body(), "box/", "")
    assert scene.compile().nmesh == 2


def test_inline_meshes_makes_spec_file_free(tmp_path):
    trimesh.creation.box((0.2, 0.2, 0.2)).export(tmp_path / "outer.stl")
    path = write(tmp_path / "drawer.urdf", drawer_urdf('<mesh filename="outer.stl"/>'))
    spec = load_articulation_spec(path, inline_meshes=True)
    assert all(m.file == "" for m in spec.meshes)
    os.remove(tmp_path / "outer.stl")
    assert mujoco.MjSpec.from_string(spec.to_xml()).compile().nmesh == 1


def test_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_articulation_spec(tmp_path / "nope.urdf")
    with pytest.raises(ValueError, match="expected a .urdf"):
        load_articulation_spec(write(tmp_path / "model.sdf", "<sdf/>"))
    with pytest.raises(FileNotFoundError, match="missing.stl"):
        load_articulation_spec(write(tmp_path / "d.urdf", drawer_urdf('<mesh filename="missing.stl"/>')))
