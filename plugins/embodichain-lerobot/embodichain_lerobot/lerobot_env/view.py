"""One embodichain env as the single env lerobot's vector env steps (``gym.make`` entry point).

lerobot's env factory (0.4.x) builds ``--eval.batch_size`` envs with ``gym.make(cfg.gym_id,
**cfg.gym_kwargs)`` and steps them in a ``gymnasium.vector.SyncVectorEnv`` with same-step
autoreset; it cannot take one batched env. So each :class:`LeRobotEnvView` is a task built
with ``num_envs=1`` (as ``embodichain run-env`` builds it, recording off), unbatched by
:class:`~embodichain_core.gym_vector.UnbatchedEnv`, with its observation in the layout
lerobot's ``preprocess_observation`` reads:

=====================================  ==============================  =====================
recorded feature (the recorder's name)  key of this env's observation   policy input in lerobot
=====================================  ==============================  =====================
``observation.state``                  ``agent_pos``                   ``observation.state``
``observation.environment_state``      ``environment_state``           ``observation.environment_state``
``observation.images.<cam>``           ``pixels/<cam>`` (H, W, 3)      ``observation.images.<cam>``
=====================================  ==============================  =====================

The info of an episode's last step has ``is_success`` (the env's ``success`` flag), which
lerobot reads from ``info["final_info"]``; ``render()`` is the colour cameras side by side.
"""

from __future__ import annotations

import argparse
from typing import Any, Optional, Sequence

import gymnasium as gym
import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.gym_vector import UnbatchedEnv
from embodichain_lerobot.env_state import ENV_STATE, state_keys_of
from embodichain_lerobot.eval_cli import recorded_instruction
from embodichain_lerobot.features import FeatureSpec, Source, flatten_obs

__all__ = ["LeRobotEnvView", "make_view", "build_env", "lerobot_sources", "GYM_ID"]

#: The gym id lerobot's factory builds (``gym.make(GYM_ID, **gym_kwargs)``).
GYM_ID = "embodichain_lerobot/EnvView-v0"
#: Recorded feature name -> the observation key lerobot's ``preprocess_observation`` maps to it.
_LEROBOT_KEYS = {"observation.state": "agent_pos", ENV_STATE: "environment_state"}
_IMAGES = "observation.images."


def lerobot_key(source: Source) -> Optional[str]:
    """The key of ``source`` in the view's observation (``pixels/<cam>`` for cameras), or
    ``None`` when lerobot's rollout cannot pass it to a policy."""
    if source.name in _LEROBOT_KEYS:
        return _LEROBOT_KEYS[source.name]
    if source.kind == "image" and source.name.startswith(_IMAGES):
        return "pixels/" + source.name[len(_IMAGES) :]
    return None


def lerobot_sources(spec: FeatureSpec) -> dict[str, Source]:
    """``{view observation key: source}`` of the recorded streams lerobot can use."""
    out = {}
    for source in spec.sources:
        key = lerobot_key(source)
        if key is not None:
            out[key] = source
    return out


def build_env(
    task: Optional[str], gym_config: Optional[str], seed: Optional[int] = None, max_steps: Optional[int] = None
) -> tuple[Any, Any]:
    """``(env, cfg)``: the task built as ``run-env`` builds it, ``num_envs=1``, headless,
    recording off (``cfg`` is its env config, ``None`` for a task without one)."""
    from embodichain_core.cli import run_env
    from embodichain_core.gym_utils import GIVEN_ATTR

    given: dict[str, Any] = {"filter_dataset_saving": True, "num_envs": 1, "headless": True}
    if seed is not None:
        given["seed"] = seed
    ns = argparse.Namespace(task=task, gym_config=gym_config or "", max_steps=max_steps, quiet=True, **given)
    setattr(ns, GIVEN_ATTR, set(given))
    plan = run_env.prepare(ns)
    if plan.cfg is not None:
        plan.cfg.num_envs = 1
    return run_env.make_env(plan), plan.cfg


def feature_spec(env: Any, cfg: Any, seed: Optional[int], state_keys: Optional[Sequence[str]] = None) -> FeatureSpec:
    """The recorder's features of ``env`` (reset once with ``seed``), with its action;
    ``observation.environment_state`` of the config recorder's list, else of ``state_keys``."""
    obs, _ = env.reset(seed=seed)
    keys = state_keys_of(getattr(cfg, "dataset", None)) or list(state_keys or [])
    spec = FeatureSpec(obs, env.unwrapped, environment_state=keys)
    spec.set_action(np.zeros((1, _action_dim(env)), np.float32))
    return spec


def _action_dim(env: Any) -> int:
    space = env.unwrapped.single_action_space
    if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
        raise ConfigError("env.task", f"lerobot's rollout sends a flat action vector; this task's action is {space}")
    return int(space.shape[0])


class LeRobotEnvView(gym.Wrapper):
    """A ``num_envs=1`` embodichain env in the single-env layout lerobot's rollout reads.

    Args:
        env: the task's env, built with ``num_envs=1`` (:func:`build_env`).
        cfg: its env config (the recorder's ``environment_state`` and instruction).
        seed: the seed of the reset that fixes the observation layout.
        state_keys: the ``environment_state`` keys when the config's recorder lists none.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"]}

    def __init__(
        self, env: Any, cfg: Any = None, seed: Optional[int] = None, state_keys: Optional[Sequence[str]] = None
    ):
        self.feature_spec = feature_spec(env, cfg, seed, state_keys)
        self.sources = lerobot_sources(self.feature_spec)
        super().__init__(UnbatchedEnv(env))
        base = env.unwrapped
        self.cameras = [k for k in self.sources if k.startswith("pixels/")]
        self.action_space = gym.spaces.Box(-np.inf, np.inf, (int(self.feature_spec.action_dim or 0),), np.float32)
        self.observation_space = self._space()
        self.metadata = {"render_modes": ["rgb_array"], "render_fps": int(base.metadata.get("render_fps") or 30)}
        #: lerobot's rollout runs at most this many steps (``env.call("_max_episode_steps")``).
        self._max_episode_steps = int(base.max_episode_steps)
        #: given to the policy as ``"task"`` (the recorder's instruction, as ``eval-policy`` does).
        self.task_description = recorded_instruction(cfg) or ""
        #: the task id (lerobot warns when an env has no ``task``).
        self.task = str(getattr(env.spec, "id", "") or "")
        self._last: dict[str, Any] = {}
        self._scene: Optional[Any] = None  # the scene renderer of an env without a colour camera

    @property
    def render_mode(self) -> str:  # type: ignore[override]
        """``"rgb_array"``: :meth:`render` returns a frame."""
        return "rgb_array"

    def _space(self) -> gym.spaces.Dict:
        spaces: dict[str, Any] = {}
        pixels: dict[str, gym.Space] = {}
        for key, s in self.sources.items():
            if key.startswith("pixels/"):
                pixels[key.split("/", 1)[1]] = gym.spaces.Box(0, 255, s.shape, np.uint8)
            else:
                spaces[key] = gym.spaces.Box(-np.inf, np.inf, s.shape, np.float32)
        if pixels:
            spaces["pixels"] = gym.spaces.Dict(pixels)
        return gym.spaces.Dict(spaces)

    def _obs(self, row: Any) -> dict[str, Any]:
        flat = {k: np.asarray(v)[None] for k, v in flatten_obs(row).items()}  # a batch of one
        out: dict[str, Any] = {}
        for key, s in self.sources.items():
            value = s.take(flat, 1)[0]
            if key.startswith("pixels/"):
                out.setdefault("pixels", {})[key.split("/", 1)[1]] = value
            else:
                out[key] = np.asarray(value, dtype=np.float32)
        self._last = out
        return out

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict[str, Any]] = None) -> tuple[Any, dict]:
        """Reset (``seed`` reseeds the env: its episode seed is ``derive_seed(seed, 0, 0)``)."""
        obs, info = self.env.reset(seed=seed, options=options)
        return self._obs(obs), {"is_success": bool(info.get("success", False))}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        """Step with an ``(action_dim,)`` action; ``is_success`` is the env's ``success``."""
        obs, reward, terminated, truncated, info = self.env.step(np.asarray(action, dtype=np.float32))
        return self._obs(obs), float(reward), terminated, truncated, {"is_success": bool(info.get("success", False))}

    def render(self) -> np.ndarray:
        """The colour cameras of the last observation side by side, ``(H, W, 3)`` uint8; the
        scene from MuJoCo's free camera when the env has none (:mod:`.frames`)."""
        if self.cameras:
            return np.concatenate([self._last["pixels"][k.split("/", 1)[1]] for k in self.cameras], axis=1)
        if self._scene is None:
            from embodichain_lerobot.lerobot_env.frames import SceneFrames

            self._scene = SceneFrames(self.env)
        return self._scene()

    def close(self) -> None:
        """Close the env (and the scene renderer)."""
        if self._scene is not None:
            self._scene.close()
        super().close()


def make_view(
    task: Optional[str] = None,
    gym_config: Optional[str] = None,
    seed: Optional[int] = None,
    max_steps: Optional[int] = None,
    environment_state: Optional[Sequence[str]] = None,
) -> LeRobotEnvView:
    """The entry point of :data:`GYM_ID`: ``gym.make(GYM_ID, task=..., gym_config=...)``."""
    env, cfg = build_env(task, gym_config, seed, max_steps)
    try:
        return LeRobotEnvView(env, cfg, seed, environment_state)
    except BaseException:
        env.close()
        raise
