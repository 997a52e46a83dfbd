"""Randomization functors (events): physics, spatial, visual and geometry.

Example:
    >>> import embodichain_functors.randomization as rand
    >>> EventCfg(func=rand.randomize_light, mode="interval", interval_step=5,
    ...          params={"entity_cfg": SceneEntityCfg(uid="point"), "intensity_range": [-5, 5]})
"""

from embodichain_functors.randomization.geometry import (
    randomize_rigid_object_scale,
    randomize_rigid_objects_scale,
)
from embodichain_functors.randomization.physics import (
    randomize_articulation_mass,
    randomize_joint_damping,
    randomize_joint_drive,
    randomize_joint_stiffness,
    randomize_rigid_object_center_of_mass,
    randomize_rigid_object_friction,
    randomize_rigid_object_mass,
)
from embodichain_functors.randomization.spatial import (
    get_random_pose,
    planner_grid_cell_sampler,
    randomize_anchor_height,
    randomize_articulation_root_pose,
    randomize_rigid_object_pose,
    randomize_robot_eef_pose,
    randomize_robot_qpos,
    randomize_target_pose,
)
from embodichain_functors.randomization.visual import (
    randomize_camera_extrinsics,
    randomize_camera_intrinsics,
    randomize_light,
    randomize_visual_material,
    set_rigid_object_group_visual_material,
    set_rigid_object_visual_material,
)

__all__ = [
    "randomize_rigid_object_mass",
    "randomize_rigid_object_center_of_mass",
    "randomize_articulation_mass",
    "randomize_rigid_object_friction",
    "randomize_joint_damping",
    "randomize_joint_stiffness",
    "randomize_joint_drive",
    "get_random_pose",
    "randomize_rigid_object_pose",
    "randomize_robot_qpos",
    "randomize_robot_eef_pose",
    "randomize_articulation_root_pose",
    "randomize_target_pose",
    "planner_grid_cell_sampler",
    "randomize_anchor_height",
    "randomize_light",
    "randomize_visual_material",
    "set_rigid_object_visual_material",
    "set_rigid_object_group_visual_material",
    "randomize_camera_extrinsics",
    "randomize_camera_intrinsics",
    "randomize_rigid_object_scale",
    "randomize_rigid_objects_scale",
]
