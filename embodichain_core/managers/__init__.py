"""Managers and the functor contract."""

from embodichain_core.managers.action_manager import ActionManager
from embodichain_core.managers.cfg import (
    ActionTermCfg,
    DatasetFunctorCfg,
    EventCfg,
    FunctorCfg,
    ObservationCfg,
    RewardCfg,
    SceneEntityCfg,
)
from embodichain_core.managers.dataset_manager import DatasetManager
from embodichain_core.managers.event_manager import EventManager
from embodichain_core.managers.functor import ActionTerm, DatasetFunctor, Functor
from embodichain_core.managers.observation_manager import ObservationManager
from embodichain_core.managers.param_rules import DataPath
from embodichain_core.managers.reward_manager import RewardManager

__all__ = [
    "ActionManager",
    "ActionTerm",
    "ActionTermCfg",
    "DatasetFunctor",
    "DatasetFunctorCfg",
    "DatasetManager",
    "DataPath",
    "EventCfg",
    "EventManager",
    "Functor",
    "FunctorCfg",
    "ObservationCfg",
    "ObservationManager",
    "RewardCfg",
    "RewardManager",
    "SceneEntityCfg",
]
