"""Small inline scenes shared by the core tests (no plugin needed)."""

ARM_MJCF = """
<mujoco model="arm3">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <geom type="cylinder" size="0.06 0.03" rgba="0.3 0.3 0.3 1"/>
      <body name="link1" pos="0 0 0.06">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.03"/>
        <body name="link2" pos="0 0 0.2">
          <joint name="j2" type="hinge" axis="0 1 0" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.025"/>
          <body name="link3" pos="0.2 0 0">
            <joint name="j3" type="hinge" axis="0 1 0" range="-2 2"/>
            <geom type="capsule" fromto="0 0 0 0.15 0 0" size="0.02"/>
            <body name="ee" pos="0.15 0 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def seven_dof_arm_mjcf() -> str:
    """A 7-DoF arm with a two-finger gripper (mimic second finger): the core's demo arm."""
    from embodichain_core.demo.arm import arm7_mjcf

    return arm7_mjcf()


DRAWER_URDF = """<?xml version="1.0"?>
<robot name="drawer">
  <link name="outer_box">
    <inertial><mass value="3"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.005"/><geometry><box size="0.4 0.36 0.01"/></geometry></collision>
  </link>
  <link name="inner_drawer">
    <inertial><mass value="0.5"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.03"/><geometry><box size="0.3 0.3 0.01"/></geometry></collision>
  </link>
  <link name="handle_xpos"/>
  <joint name="slide_rails" type="prismatic">
    <parent link="outer_box"/><child link="inner_drawer"/><origin xyz="0 0 0.02"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.2" effort="100" velocity="1"/><dynamics damping="1"/>
  </joint>
  <joint name="handle_fixed" type="fixed">
    <parent link="inner_drawer"/><child link="handle_xpos"/><origin xyz="0.18 0 0.05" rpy="0 -1.5708 0"/>
  </joint>
</robot>
"""
