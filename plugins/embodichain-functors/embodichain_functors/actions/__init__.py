"""Action terms: turn the policy action into robot commands (``ActionTermCfg(func=...)``).

Every term acts on the env's active joints (``control_parts`` or
``active_joint_ids``; mimic joints follow their parents) and returns commands of
that width. ``QvelTerm`` and ``QfTerm`` really drive velocity and effort: the
action manager routes their output by ``input_key`` to the velocity drives and to
the applied joint forces.

Example:
    >>> import embodichain_functors.actions as actions
    >>> ActionTermCfg(func=actions.DeltaQposTerm, params={"scale": 0.1})
"""

from embodichain_functors.actions.drive import DEFAULT_QF_LIMIT, DEFAULT_QVEL_LIMIT, QfTerm, QvelTerm
from embodichain_functors.actions.eef import EefPoseTerm
from embodichain_functors.actions.position import DeltaQposTerm, QposDenormalizedTerm, QposNormalizedTerm, QposTerm

__all__ = [
    "DeltaQposTerm",
    "QposTerm",
    "QposDenormalizedTerm",
    "QposNormalizedTerm",
    "EefPoseTerm",
    "QvelTerm",
    "QfTerm",
    "DEFAULT_QVEL_LIMIT",
    "DEFAULT_QF_LIMIT",
]
