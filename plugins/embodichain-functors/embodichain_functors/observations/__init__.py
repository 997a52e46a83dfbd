"""Observation functors: ``add`` functors ``f(env, obs, **params) -> value`` and the
``modify`` functor ``normalize_robot_joint_data(env, data, **params) -> new data``.

One module per topic; each lists its public names in ``__all__``, which this
package re-exports: :mod:`.objects` (poses, velocity, scale, target position),
:mod:`.robot` (joint data, end effector), :mod:`.sensors` (camera pose,
intrinsics, semantic mask), :mod:`.physics` (cached physical attributes).

Example:
    >>> import embodichain_functors.observations as obs
    >>> ObservationCfg(func=obs.get_rigid_object_pose, mode="add", name="fork_pose",
    ...                params={"entity_cfg": SceneEntityCfg(uid="fork")})
"""

from embodichain_functors.observations import objects, physics, robot, sensors
from embodichain_functors.observations.objects import *  # noqa: F403
from embodichain_functors.observations.physics import *  # noqa: F403
from embodichain_functors.observations.robot import *  # noqa: F403
from embodichain_functors.observations.sensors import *  # noqa: F403

__all__: list[str] = []
__all__ += objects.__all__
__all__ += robot.__all__
__all__ += sensors.__all__
__all__ += physics.__all__
