"""``observation.environment_state``: task observations as one flat state vector.

lerobot's state-based policies (ACT, Diffusion) read ``observation.state`` (the robot)
and ``observation.environment_state`` (the world), besides images. A LeRobot recorder's
``params.environment_state`` lists observation keys (flattened with ``/``, as
:func:`~embodichain_lerobot.features.flatten_obs` names them: ``fork_pose``,
``robot/eef_pose``, ...); their values are flattened and concatenated in that order into
one float32 feature ``observation.environment_state`` whose ``names`` say where each
element comes from (``fork_pose[0,3]``), and they are not recorded under their own
names. ``eval-policy`` and ``dataset replay`` build the same vector from the env's
observations with the same code (:class:`StateSource`, through
:class:`~embodichain_lerobot.features.FeatureSpec`), reading the list from the gym
config's dataset section (:func:`state_keys_of`); ``eval-policy`` in a config without
one reads it from the names of the dataset the policy was trained on
(:func:`trained_state_keys`).

Config::

    "dataset": {"lerobot": {"func": "LeRobotRecorder", "params": {
        "environment_state": ["fork_pose"], ...}}}
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean

__all__ = [
    "ENV_STATE",
    "StateSource",
    "check_state_keys",
    "keys_from_names",
    "state_keys_of",
    "state_source",
    "trained_state_keys",
]

#: The feature name lerobot policies read as the environment state.
ENV_STATE = "observation.environment_state"


def check_state_keys(value: Any, key: str = "environment_state") -> list[str]:
    """``params.environment_state`` as a list of observation keys (``None``: empty).

    Raises:
        ConfigError: not a list of distinct non-empty strings.
    """
    if value is None:
        return []
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise ConfigError(key, f"must be a list of observation keys, got {value!r}")
    keys = list(value)
    if not all(isinstance(k, str) and k for k in keys) or len(set(keys)) != len(keys):
        raise ConfigError(key, f"must list distinct observation keys (strings), got {keys!r}")
    return keys


def state_keys_of(dataset: Any) -> list[str]:
    """The ``environment_state`` keys of the first dataset functor that has them.

    Args:
        dataset: a gym config's ``dataset`` section: functor configs or their plain dicts
            (as ``meta/embodichain_env.json`` stores them); ``None``: no section.
    """
    for name, functor in dict(dataset or {}).items():
        params = functor.get("params") if isinstance(functor, Mapping) else getattr(functor, "params", None)
        keys = (params or {}).get("environment_state")
        if keys:
            return check_state_keys(keys, f"dataset.{name}.params.environment_state")
    return []


def keys_from_names(names: Sequence[str]) -> list[str]:
    """The observation keys of ``observation.environment_state``'s element names, in order."""
    keys: list[str] = []
    for name in names:
        key = str(name).split("[", 1)[0]
        if key not in keys:
            keys.append(key)
    return keys


def trained_state_keys(policy_dir: str | Path) -> list[str]:
    """The ``environment_state`` keys of the dataset a ``lerobot-train`` policy was trained on.

    Read from the policy's ``train_config.json`` (its ``dataset.root``) and that dataset's
    feature names; empty when either is not there.
    """
    try:
        train = json.loads((Path(policy_dir) / "train_config.json").read_text(encoding="utf-8"))
        info = Path(train["dataset"]["root"]) / "meta" / "info.json"
        names = json.loads(info.read_text(encoding="utf-8"))["features"][ENV_STATE]["names"]
    except (OSError, KeyError, TypeError, ValueError):
        return []
    return keys_from_names(names or [])


def _element_names(key: str, shape: tuple) -> list[str]:
    if shape == (1,):
        return [key]
    return [f"{key}[{','.join(map(str, idx))}]" for idx in np.ndindex(*shape)]


class StateSource:
    """The ``observation.environment_state`` stream: several numeric observations in one vector.

    It has the attributes of :class:`~embodichain_lerobot.features.Source` that the
    recorder and the policy mapping read (``name``, ``kind``, ``shape``, ``names``, ...).
    """

    kind = "numeric"
    dtype = "float32"
    lossless_video = False

    def __init__(self, parts: Sequence[Any]):
        self.parts = list(parts)
        self.name = ENV_STATE
        self.key = ",".join(p.key for p in self.parts)
        self.names = [n for p in self.parts for n in _element_names(p.key, tuple(p.shape))]
        self.shape = (len(self.names),)

    def take(self, flat: Mapping[str, Any], num_envs: int) -> np.ndarray:
        """``(N, D)`` float32: each part's value flattened, in the configured order."""
        cols = [p.convert(flat[p.key], num_envs).reshape(num_envs, -1) for p in self.parts]
        return np.concatenate(cols, axis=1).astype(np.float32, copy=False)

    def feature(self, use_videos: bool) -> dict:
        """The lerobot feature dict (float32, named by element)."""
        return {"dtype": self.dtype, "shape": self.shape, "names": list(self.names)}


def state_source(sources: list, keys: Sequence[str]) -> tuple[list, Optional[StateSource]]:
    """Move the sources of ``keys`` into one :class:`StateSource` (last in the list).

    Raises:
        ConfigError: ``environment_state``: a key the observation does not have (with the
            closest one), or a camera stream.
    """
    if not keys:
        return sources, None
    by_key = {s.key: s for s in sources}
    parts = []
    for key in keys:
        source = by_key.get(key)
        if source is None:
            numeric = [s.key for s in sources if s.kind == "numeric"]
            raise ConfigError(
                "environment_state",
                f"the observation has no {key!r}.{did_you_mean(key, numeric)} Numeric observations: {numeric}",
            )
        if source.kind != "numeric":
            raise ConfigError("environment_state", f"{key!r} is a camera stream, not a numeric observation")
        parts.append(source)
    state = StateSource(parts)
    return [s for s in sources if s.key not in set(keys)] + [state], state
