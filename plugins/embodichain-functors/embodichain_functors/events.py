"""Event functors ``f(env, env_ids, **params)``: asset swaps, attribute and pose
registration, settling, detached reset uids, group drops, rigid constraints.

Example:
    >>> import embodichain_functors.events as events
    >>> EventCfg(func=events.replace_assets_from_group, mode="reset",
    ...          params={"entity_cfg": SceneEntityCfg(uid="fork"), "folder_path": "TableWare/tableware/fork/"})
"""

from embodichain_functors.event_functors.assets import (
    drop_rigid_object_group_sequentially,
    replace_assets_from_group,
    set_detached_uids_for_env_reset,
)
from embodichain_functors.event_functors.constraints import create_rigid_constraint, remove_rigid_constraint
from embodichain_functors.event_functors.registration import (
    get_pose,
    prepare_extra_attr,
    register_entity_attrs,
    register_entity_pose,
    register_info_to_env,
    resolve_dict,
    resolve_uids,
)
from embodichain_functors.event_functors.settling import wait_for_dynamic_objects_to_settle

__all__ = [
    "replace_assets_from_group", "prepare_extra_attr", "register_entity_attrs", "register_entity_pose",
    "register_info_to_env", "resolve_uids", "resolve_dict", "get_pose", "drop_rigid_object_group_sequentially",
    "wait_for_dynamic_objects_to_settle", "set_detached_uids_for_env_reset", "create_rigid_constraint",
    "remove_rigid_constraint",
]
