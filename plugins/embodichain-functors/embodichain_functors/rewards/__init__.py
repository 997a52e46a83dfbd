"""Reward functors ``f(env, obs, action, info, **params) -> (N,)``.

One module per topic; each lists its public names in ``__all__``, which this
package re-exports: :mod:`.distance` (distances, alignment, reaching), :mod:`.penalty`
(joint velocity, joint limits, action smoothness), :mod:`.task` (success). The
stateful ones (``incremental_distance_to_target``, ``action_smoothness_penalty``)
are class functors whose state is cleared for the envs being reset.

Example:
    >>> import embodichain_functors.rewards as rewards
    >>> RewardCfg(func=rewards.distance_to_target, weight=0.8,
    ...           params={"source_entity_cfg": SceneEntityCfg(uid="cube"), "target_pose_key": "goal_pose"})
"""

from embodichain_functors.rewards import distance, penalty, task
from embodichain_functors.rewards.distance import *  # noqa: F403
from embodichain_functors.rewards.penalty import *  # noqa: F403
from embodichain_functors.rewards.task import *  # noqa: F403

__all__: list[str] = []
__all__ += distance.__all__
__all__ += penalty.__all__
__all__ += task.__all__
