"""A fixture event functor."""

import torch


def fixture_nudge_cube(env, env_ids, entity_cfg, offset_range=(-0.05, 0.05)):
    """Shift ``entity_cfg``'s x by a per-env random offset in ``offset_range``."""
    obj = env.scene[entity_cfg.uid]
    pose = obj.get_local_pose()[env_ids]
    low, high = offset_range
    pose[:, 0] += low + (high - low) * torch.rand(len(env_ids), generator=env.generator)
    obj.set_local_pose(pose, env_ids)
