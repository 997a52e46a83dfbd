"""Env observations as a LeRobot policy's input batch, through the recorder's feature mapping.

:class:`~embodichain_lerobot.features.FeatureSpec` (what ``LeRobotRecorder`` uses) names
every observation stream as a dataset feature (``robot/qpos`` -> ``observation.state``,
``sensor/<cam>/color`` -> ``observation.images.<cam>``, ...). A policy trained on such a
dataset has those names as its input features, so the same mapping gives its inputs:
numeric streams as float32 ``(N, *shape)``, image features (colour, and depth and masks
packed into RGB as the recorder stores them) as float32 ``(N, 3, H, W)`` in [0, 1] (what
LeRobot's dataset loader gives the policy during training). Depth and masks recorded with
``depth_format: "raw"`` are numeric: a policy that has them as state inputs gets them so.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_lerobot.env_state import ENV_STATE, state_keys_of
from embodichain_lerobot.features import IMAGE_KINDS, FeatureSpec, Source, flatten_obs

__all__ = ["ObservationMapper", "policy_inputs"]


def policy_inputs(config: Any) -> dict[str, tuple[str, tuple[int, ...]]]:
    """``{feature name: (type, shape)}`` of a policy config's observation inputs."""
    return {
        name: (str(getattr(ft.type, "value", ft.type)), tuple(int(s) for s in ft.shape))
        for name, ft in (config.input_features or {}).items()
    }


def _expected_shape(source: Source) -> tuple[int, ...]:
    """The shape a policy trained on the recorded feature expects (images channel-first)."""
    if source.kind in IMAGE_KINDS:
        h, w, c = source.shape
        return (c, h, w)
    return tuple(source.shape)


def _depth_format(wanted: dict[str, tuple[str, tuple[int, ...]]]) -> str:
    """``"raw"`` when the policy has depth or mask inputs as numbers, else ``"png16"`` (images)."""
    maps = [kind for name, (kind, _) in wanted.items() if name.startswith(("observation.depth.", "observation.mask."))]
    return "raw" if maps and all(kind != "VISUAL" for kind in maps) else "png16"


def _describe(features: dict[str, tuple[int, ...]]) -> str:
    return ", ".join(f"{name} {list(shape)}" for name, shape in sorted(features.items())) or "(none)"


class ObservationMapper:
    """Maps batched env observations to the input batch of a policy.

    Args:
        obs: a batched observation of the env (``(N, ...)`` tensors), e.g. from ``reset``.
        env: the unwrapped env (joint names, sensors), as for the recorder.
        config: the policy's ``PreTrainedConfig`` (its ``input_features``).
        instruction: the language instruction, given as the batch's ``"task"`` (one string
            per env, as lerobot's own eval does for language-conditioned policies).
        environment_state: the observation keys of ``observation.environment_state``
            (default: the ``environment_state`` of the env config's LeRobot recorder).

    Raises:
        ConfigError: ``policy``: the env lacks an input of the policy, or has it with another
            shape; the message lists the policy's inputs and the env's features.
    """

    def __init__(
        self,
        obs: Any,
        env: Any,
        config: Any,
        instruction: str | None = None,
        environment_state: Sequence[str] | None = None,
    ):
        self.instruction = instruction
        wanted = policy_inputs(config)
        state_keys = environment_state
        if state_keys is None:
            state_keys = state_keys_of(getattr(getattr(env, "cfg", None), "dataset", None))
        self.spec = FeatureSpec(obs, env, depth_format=_depth_format(wanted), environment_state=state_keys)
        self.num_envs = self.spec.num_envs
        by_name = {s.name: s for s in self.spec.sources}
        env_shapes = {name: _expected_shape(s) for name, s in by_name.items()}
        problems = []
        for name, (kind, shape) in wanted.items():
            if name not in by_name:
                hint = (
                    " (the config's LeRobot recorder names it: params.environment_state)" if name == ENV_STATE else ""
                )
                problems.append(f"{name} {list(shape)} is missing{hint}")
            elif env_shapes[name] != shape:
                problems.append(f"{name} is {list(shape)} for the policy, {list(env_shapes[name])} in the env")
            elif (kind == "VISUAL") != (by_name[name].kind in IMAGE_KINDS):
                problems.append(f"{name} is {kind} for the policy, {by_name[name].kind} in the env")
        if problems:
            raise ConfigError(
                "policy",
                "the policy's inputs do not match the env's observations: "
                + "; ".join(problems)
                + f". Policy inputs: {_describe({k: v[1] for k, v in wanted.items()})}. "
                + f"Env features (the recorder's names): {_describe(env_shapes)}",
            )
        self.sources = [by_name[name] for name in wanted]
        self.cameras = [s for s in self.spec.sources if s.kind == "image"]

    def __call__(self, obs: Any) -> dict[str, Any]:
        """The policy's input batch (float32 tensors on the CPU, and ``"task"`` with an
        instruction) of a batched observation."""
        flat = flatten_obs(obs)
        batch: dict[str, Any] = {}
        if self.instruction is not None:
            batch["task"] = [self.instruction] * self.num_envs
        for s in self.sources:
            arr = s.take(flat, self.num_envs)
            if s.kind in IMAGE_KINDS:
                tensor = torch.from_numpy(arr).permute(0, 3, 1, 2).float().div_(255.0)
            else:
                tensor = torch.from_numpy(np.ascontiguousarray(arr, dtype=np.float32))
            batch[s.name] = tensor.contiguous()
        return batch

    def frames(self, obs: Any) -> dict[str, np.ndarray]:
        """The colour camera images ``{feature name: (N, H, W, 3) uint8}`` of an observation."""
        flat = flatten_obs(obs)
        return {s.name: s.convert(flat[s.key], self.num_envs) for s in self.cameras}
