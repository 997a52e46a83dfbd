"""``--env.type=embodichain``: the lerobot ``EnvConfig`` of every embodichain task."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from draccus.utils import ParsingError
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig

from embodichain_core.config.errors import ConfigError
from embodichain_lerobot.lerobot_env.checks import check_inputs, check_task, required_inputs, trained_state_keys
from embodichain_lerobot.lerobot_env.view import GYM_ID, build_env, feature_spec, lerobot_sources

__all__ = ["EmbodiChainEnv", "ENV_TYPE", "EnvConfigError"]

#: The name ``--env.type`` selects.
ENV_TYPE = "embodichain"


class EnvConfigError(ParsingError):
    """A bad ``--env.*`` value or a policy the env cannot run, raised while lerobot parses
    its command line. A draccus ``ParsingError``: lerobot's parser passes it on as it is
    (it would wrap any other error in two more messages).

    Attributes:
        path: the key (``env.task``, ``policy``), as in :class:`ConfigError`.
    """

    def __init__(self, err: ConfigError):
        self.path = err.path
        super().__init__(str(err))


@EnvConfig.register_subclass(ENV_TYPE)
@dataclass
class EmbodiChainEnv(EnvConfig):
    """An embodichain task for ``lerobot-eval`` and ``lerobot-train``'s evaluation.

    Building the config builds the task once (one env) to read its observations, so
    ``features``/``features_map`` are the recorder's names of what the env gives; it checks
    the task and that the policy (``--policy.path``) or the training dataset
    (``--dataset.root``) reads only inputs the env has. ``fps`` becomes the env's control rate.

    Attributes:
        task: the gym task id (``PickFork-v1``), built with the config it ships.
        gym_config: a gym config file (JSON/YAML) instead of, or with, ``task``.
        seed: the env config's seed (randomness before the first reset); lerobot seeds
            each episode itself (``--seed``: episode ``k`` resets with ``seed + k``).
        max_steps: the episode step limit (default: the config's ``max_episode_steps``).
        environment_state: the observation keys of ``observation.environment_state``
            (default: the config recorder's list, else the names of the dataset the policy
            was trained on, as ``eval-policy`` reads them).
        fps: replaced by the env's control rate.
    """

    task: Optional[str] = None
    gym_config: Optional[str] = None
    seed: Optional[int] = None
    max_steps: Optional[int] = None
    environment_state: Optional[list[str]] = field(default=None)
    fps: int = 30  # replaced by the env's control rate (its render_fps)

    def __post_init__(self) -> None:
        try:
            self._check()
        except ConfigError as err:
            raise EnvConfigError(err) from None

    def _check(self) -> None:
        if not self.gym_config:
            check_task(self.task)
        if self.environment_state is None:
            self.environment_state = trained_state_keys()
        if not self.features:
            self._read_env()
        where, inputs = required_inputs()
        if inputs:
            given = {self.features_map[k]: _policy_shape(ft) for k, ft in self.features.items() if k != "action"}
            check_inputs(where, inputs, given)

    def _read_env(self) -> None:
        env, cfg = build_env(self.task, self.gym_config, self.seed, self.max_steps)
        try:
            spec = feature_spec(env, cfg, self.seed, self.environment_state)
            self.fps = int(env.unwrapped.metadata.get("render_fps") or self.fps)
        finally:
            env.close()
        sources = lerobot_sources(spec)
        self.features = {"action": PolicyFeature(FeatureType.ACTION, (int(spec.action_dim or 0),))}
        self.features_map = {"action": "action"}
        for key, s in sources.items():
            kind = FeatureType.VISUAL if key.startswith("pixels/") else _state_type(s.name)
            self.features[key] = PolicyFeature(kind, tuple(s.shape))
            self.features_map[key] = s.name

    @property
    def package_name(self) -> str:
        """The module that registers :data:`GYM_ID` (imported by lerobot when it is missing)."""
        return "embodichain_lerobot.lerobot_env"

    @property
    def gym_id(self) -> str:
        """The one gym id of every task (the task travels in :attr:`gym_kwargs`)."""
        return GYM_ID

    @property
    def gym_kwargs(self) -> dict[str, Any]:
        """What :func:`~embodichain_lerobot.lerobot_env.view.make_view` builds."""
        keys = self.environment_state
        return {
            "task": self.task,
            "gym_config": self.gym_config,
            "seed": self.seed,
            "max_steps": self.max_steps,
            "environment_state": keys,
        }


def _state_type(name: str) -> FeatureType:
    return FeatureType.ENV if name == "observation.environment_state" else FeatureType.STATE


def _policy_shape(ft: PolicyFeature) -> tuple[int, ...]:
    """The shape the policy sees (images channel-first, as lerobot converts them)."""
    if ft.type is FeatureType.VISUAL:
        h, w, c = ft.shape
        return (c, h, w)
    return tuple(ft.shape)
