"""The functors this plugin registers: one line each, ``name: category``, under its public module.

:mod:`embodichain_functors.plugin` registers them lazily, as ``"module:name"`` targets: no
functor module is imported until a config names one. A functor's description is the
first line of its docstring, read from the module's source files without importing
them (:func:`first_doc_lines`); ``scripts/gen_catalogue.py`` builds
docs/functor_catalogue.md from the registry.

Adding a functor: write it in its kind's module (listed in that module's ``__all__``,
which the public package re-exports) and add its line to :data:`REGISTRATIONS`.
"""

from __future__ import annotations

import functools
import ast
from pathlib import Path

#: public module -> (functor kind, {registered name: category}); the name is the attribute.
REGISTRATIONS: dict[str, tuple[str, dict[str, str]]] = {
    "embodichain_functors.events": (
        "event",
        {
            "replace_assets_from_group": "asset",
            "drop_rigid_object_group_sequentially": "asset",
            "prepare_extra_attr": "registration",
            "register_entity_attrs": "registration",
            "register_entity_pose": "registration",
            "register_info_to_env": "registration",
            "set_detached_uids_for_env_reset": "reset",
            "wait_for_dynamic_objects_to_settle": "reset",
            "create_rigid_constraint": "constraint",
            "remove_rigid_constraint": "constraint",
        },
    ),
    "embodichain_functors.randomization": (
        "event",
        {
            "randomize_rigid_object_mass": "randomization.physics",
            "randomize_rigid_object_center_of_mass": "randomization.physics",
            "randomize_articulation_mass": "randomization.physics",
            "randomize_rigid_object_friction": "randomization.physics",
            "randomize_joint_damping": "randomization.physics",
            "randomize_joint_stiffness": "randomization.physics",
            "randomize_joint_drive": "randomization.physics",
            "randomize_rigid_object_pose": "randomization.spatial",
            "randomize_robot_qpos": "randomization.spatial",
            "randomize_robot_eef_pose": "randomization.spatial",
            "randomize_articulation_root_pose": "randomization.spatial",
            "randomize_target_pose": "randomization.spatial",
            "planner_grid_cell_sampler": "randomization.spatial",
            "randomize_anchor_height": "randomization.spatial",
            "randomize_light": "randomization.visual",
            "randomize_visual_material": "randomization.visual",
            "set_rigid_object_visual_material": "randomization.visual",
            "set_rigid_object_group_visual_material": "randomization.visual",
            "randomize_camera_extrinsics": "randomization.visual",
            "randomize_camera_intrinsics": "randomization.visual",
            "randomize_rigid_object_scale": "randomization.geometry",
            "randomize_rigid_objects_scale": "randomization.geometry",
        },
    ),
    "embodichain_functors.observations": (
        "observation",
        {
            "get_object_pose": "observation.object",
            "get_rigid_object_pose": "observation.object",
            "get_rigid_object_velocity": "observation.object",
            "get_object_body_scale": "observation.object",
            "normalize_robot_joint_data": "observation.robot",
            "get_robot_eef_pose": "observation.robot",
            "get_sensor_pose_in_robot_frame": "observation.sensor",
            "get_sensor_intrinsics": "observation.sensor",
            "compute_semantic_mask": "observation.sensor",
            "target_position": "observation.task",
            "get_rigid_object_physics_attributes": "observation.physics",
            "get_articulation_joint_drive": "observation.physics",
        },
    ),
    "embodichain_functors.rewards": (
        "reward",
        {
            "distance_between_objects": "reward.distance",
            "distance_to_target": "reward.distance",
            "incremental_distance_to_target": "reward.distance",
            "reaching_behind_object": "reward.distance",
            "orientation_alignment": "reward.distance",
            "joint_velocity_penalty": "reward.penalty",
            "joint_limit_penalty": "reward.penalty",
            "action_smoothness_penalty": "reward.penalty",
            "success_reward": "reward.task",
        },
    ),
    "embodichain_functors.actions": (
        "action",
        {
            "DeltaQposTerm": "action.joint",
            "QposTerm": "action.joint",
            "QposDenormalizedTerm": "action.joint",
            "QposNormalizedTerm": "action.joint",
            "QvelTerm": "action.joint",
            "QfTerm": "action.joint",
            "EefPoseTerm": "action.eef",
        },
    ),
}

_PACKAGE = Path(__file__).resolve().parent


def source_files(module: str) -> list[Path]:
    """The source files of a public module of this package (every file of a package)."""
    path = _PACKAGE.joinpath(*module.split(".")[1:])
    return sorted(path.glob("*.py")) if path.is_dir() else [path.with_suffix(".py")]


def doc_lines_of_file(path: Path) -> dict[str, str]:
    """``{name: first docstring line}`` of the top-level functions and classes of a source file.

    The file is parsed, not imported (loading the plugin imports no functor module); the
    line is the first non-empty line of the docstring (``""`` without one).
    """
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    lines: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            doc = ast.get_docstring(node, clean=False) or ""
            first = next((line.strip() for line in doc.splitlines() if line.strip()), "")
            lines.setdefault(node.name, first)
    return lines


@functools.lru_cache(maxsize=None)
def first_doc_lines(module: str) -> dict[str, str]:
    """:func:`doc_lines_of_file` of every source file of a public module (the first definition wins)."""
    lines: dict[str, str] = {}
    for path in source_files(module):
        for name, line in doc_lines_of_file(path).items():
            lines.setdefault(name, line)
    return lines


def _rows() -> list[tuple[str, str, str, str, str]]:
    return [
        (name, f"{module}:{name}", kind, category, first_doc_lines(module).get(name, ""))
        for module, (kind, functors) in REGISTRATIONS.items()
        for name, category in functors.items()
    ]


FUNCTORS: list[tuple[str, str, str, str, str]] = _rows()
"""Every registration as ``(name, "module:attr", kind, category, description)``; an empty
description (no docstring found) is filled from the docstring when the target is imported."""
