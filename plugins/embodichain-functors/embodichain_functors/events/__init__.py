"""Event functors ``f(env, env_ids, **params)``: asset swaps, attribute and pose
registration, settling, detached reset uids, group drops, rigid constraints.

One module per topic; each lists its public names in ``__all__``, which this
package re-exports: :mod:`.assets`, :mod:`.registration`, :mod:`.settling`,
:mod:`.constraints`. The randomization events are in
:mod:`embodichain_functors.randomization`.

Example:
    >>> import embodichain_functors.events as events
    >>> EventCfg(func=events.replace_assets_from_group, mode="reset",
    ...          params={"entity_cfg": SceneEntityCfg(uid="fork"), "folder_path": "TableWare/tableware/fork/"})
"""

from embodichain_functors.events import assets, constraints, registration, settling
from embodichain_functors.events.assets import *  # noqa: F403
from embodichain_functors.events.constraints import *  # noqa: F403
from embodichain_functors.events.registration import *  # noqa: F403
from embodichain_functors.events.settling import *  # noqa: F403

__all__: list[str] = []
__all__ += assets.__all__
__all__ += registration.__all__
__all__ += settling.__all__
__all__ += constraints.__all__
