"""Functor configs of the managers and ``SceneEntityCfg``."""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Union

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.configclass import MISSING, configclass
from embodichain_core.utils.suggest import did_you_mean


@configclass
class FunctorCfg:
    """A functor: ``func`` (function, ``Functor`` class, registered name or
    ``"module:attr"``) with its ``params``. ``extra`` carries hints such as
    ``{"shape": (3,)}`` for buffer preallocation."""

    func: Any = MISSING
    params: Dict[str, Any] = {}
    extra: Dict[str, Any] = {}


@configclass
class EventCfg(FunctorCfg):
    """An event: ``mode`` is ``startup``, ``reset``, ``interval`` or a custom name that
    task code triggers with ``env.event_manager.apply(mode, env_ids)``.

    ``interval`` events fire every ``interval_step`` env steps, counted per env from
    the start of its episode; with ``is_global=True`` one counter fires for all envs.
    """

    mode: str = "reset"
    interval_step: int = 10
    is_global: bool = False


@configclass
class ObservationCfg(FunctorCfg):
    """``mode="add"`` writes the functor's output at ``name`` (``a/b/c`` nests);
    ``mode="modify"`` passes the data at ``name`` and stores what it returns (or keeps
    the in-place change when it returns ``None``)."""

    mode: str = "modify"
    name: str = MISSING


@configclass
class RewardCfg(FunctorCfg):
    """A reward term; ``add`` sums ``weight * term``, ``replace`` sets the total to it."""

    mode: str = "add"
    weight: float = 1.0


@configclass
class ActionTermCfg(FunctorCfg):
    """An action term (an ``ActionTerm`` class); ``pre`` terms turn the policy action
    into robot commands, ``post`` terms transform it after the step."""

    mode: str = "pre"


@configclass
class DatasetFunctorCfg(FunctorCfg):
    """A dataset recorder; episodes are saved when they end successfully, or
    always with ``save_failed_episodes``."""

    mode: str = "save"
    save_failed_episodes: bool = False


@configclass
class SceneEntityCfg:
    """Names a scene entity and, optionally, some of its joints or bodies.

    Resolved once when the manager is built: ``joint_names`` (regexes) become
    ``joint_ids`` and ``body_names`` become ``body_ids``.

    Example:
        >>> SceneEntityCfg(uid="robot", joint_names=["joint[1-3]"])
    """

    uid: str = MISSING
    joint_names: Optional[Union[str, List[str]]] = None
    joint_ids: Any = slice(None)
    link_names: Optional[Union[str, List[str]]] = None
    control_parts: Optional[Union[str, List[str]]] = None
    body_names: Optional[Union[str, List[str]]] = None
    body_ids: Any = slice(None)
    preserve_order: bool = False

    def resolve(self, scene: Any, path: str = "") -> "SceneEntityCfg":
        """Check the uid and turn names into ids (in place); return ``self``."""
        if self.uid not in scene.asset_uids:
            raise ConfigError(
                f"{path}.uid" if path else "uid",
                f"no entity {self.uid!r} in the scene.{did_you_mean(str(self.uid), scene.asset_uids)}",
            )
        entity = scene.get(self.uid)
        if self.joint_names is not None:
            self.joint_ids = self._names_to_ids(entity, "find_joints", self.joint_names, self.joint_ids, path, "joint")
        if self.body_names is not None:
            self.body_ids = self._names_to_ids(entity, "find_bodies", self.body_names, self.body_ids, path, "body")
        return self

    def _names_to_ids(self, entity: Any, finder: str, names: Any, given: Any, path: str, what: str) -> Any:
        if not hasattr(entity, finder):
            raise ConfigError(path, f"entity {self.uid!r} has no {what}s to select by name")
        try:
            ids, _ = getattr(entity, finder)(names, self.preserve_order)
        except KeyError as err:
            raise ConfigError(f"{path}.{what}_names" if path else f"{what}_names", str(err).strip("\"'")) from err
        if given != slice(None) and list(given) != list(ids):
            raise ConfigError(
                path, f"{what}_names {names!r} resolve to {ids}, which disagrees with {what}_ids {given!r}"
            )
        return ids


FUNCTOR_CFG_TYPES: dict[str, type[FunctorCfg]] = {
    "events": EventCfg,
    "observations": ObservationCfg,
    "rewards": RewardCfg,
    "actions": ActionTermCfg,
    "dataset": DatasetFunctorCfg,
}
