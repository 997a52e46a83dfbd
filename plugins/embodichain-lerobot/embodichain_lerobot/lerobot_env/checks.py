"""Checks of ``--env.*`` before lerobot runs an episode: the task exists, and the policy
(``--policy.path``) or the dataset it is trained on (``--dataset.root``) asks only for
inputs the env gives lerobot's rollout."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

from embodichain_core.config.errors import ConfigError

__all__ = ["check_task", "required_inputs", "check_inputs", "trained_state_keys"]

#: The non-image inputs lerobot's policies read (``robot_state_feature``, ``env_state_feature``).
_READ_STATES = ("observation.state", "observation.environment_state")


def check_task(task: Optional[str]) -> None:
    """Raise :class:`ConfigError` ``env.task`` naming the task, the closest and all tasks."""
    import gymnasium as gym

    from embodichain_core.plugins import task_registry
    from embodichain_core.utils.suggest import did_you_mean

    ours = task_registry().names()  # loads the plugins, which put their tasks into gymnasium
    if task is not None and task in gym.registry:
        return
    what = "no task: give --env.task=<task id> or --env.gym_config=<file>" if task is None else f"unknown task {task!r}"
    hint = did_you_mean(task, ours) if task is not None else ""
    raise ConfigError("env.task", f"{what}.{hint} Available tasks: {', '.join(ours)}")


def _policy_inputs(folder: Path) -> dict[str, tuple[str, tuple[int, ...]]]:
    data = json.loads((folder / "config.json").read_text(encoding="utf-8"))
    return {k: (str(v["type"]), tuple(int(s) for s in v["shape"])) for k, v in data.get("input_features", {}).items()}


def _dataset_inputs(root: Path) -> dict[str, tuple[str, tuple[int, ...]]]:
    from lerobot.datasets.utils import dataset_to_policy_features

    info = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))
    for ft in info["features"].values():
        ft["shape"] = tuple(ft["shape"])
    features = dataset_to_policy_features(info["features"])
    return {k: (ft.type.name, tuple(ft.shape)) for k, ft in features.items() if ft.type.name != "ACTION"}


def _sources(args: Optional[list[str]]) -> tuple[Optional[Path], Optional[Path]]:
    """``(policy folder, dataset root)`` given on the command line (local folders only)."""
    from lerobot.configs import parser

    from embodichain_lerobot.policy_io import find_pretrained_dir

    path = parser.get_path_arg("policy", args)
    if path and Path(path).expanduser().exists():
        return find_pretrained_dir(path), None
    root = parser.parse_arg("dataset.root", args)
    if root and (Path(root) / "meta" / "info.json").is_file():
        return None, Path(root)
    return None, None


def trained_state_keys(args: Optional[list[str]] = None) -> list[str]:
    """The ``environment_state`` keys of the dataset the command's policy was (or is being)
    trained on, as ``eval-policy`` reads them for a config without the recorder's list."""
    from embodichain_lerobot import env_state

    folder, root = _sources(args)
    if folder is not None:
        return env_state.trained_state_keys(folder)
    if root is None:
        return []
    features = json.loads((root / "meta" / "info.json").read_text(encoding="utf-8"))["features"]
    return env_state.keys_from_names((features.get(env_state.ENV_STATE) or {}).get("names") or [])


def required_inputs(args: Optional[list[str]] = None) -> tuple[str, dict[str, tuple[str, tuple[int, ...]]]]:
    """``(where, {input: (type, shape)})`` of the inputs the command's policy reads: those of
    ``--policy.path``, else of the local dataset ``--dataset.root``; ``("", {})`` without either."""
    folder, root = _sources(args)
    if folder is not None:
        found = ("the policy " + str(folder), _policy_inputs(folder))
    elif root is not None:
        found = ("the dataset " + str(root), _dataset_inputs(root))
    else:
        return "", {}
    where, inputs = found
    read = {k: v for k, v in inputs.items() if v[0] == "VISUAL" or k in _READ_STATES}
    return where, read


def check_inputs(where: str, inputs: dict[str, tuple[str, tuple[int, ...]]], env: dict[str, tuple[int, ...]]) -> None:
    """Raise :class:`ConfigError` ``policy`` when an input is missing from ``env`` or has another
    shape there (``env``: ``{policy input name: shape}``, images channel-first)."""
    problems = []
    for name, (_, shape) in sorted(inputs.items()):
        if name not in env:
            problems.append(f"{name} {list(shape)} is missing")
        elif tuple(env[name]) != tuple(shape):
            problems.append(f"{name} is {list(shape)} for the policy, {list(env[name])} in the env")
    if problems:
        given = ", ".join(f"{k} {list(v)}" for k, v in sorted(env.items())) or "(none)"
        raise ConfigError(
            "policy",
            f"{where} reads inputs the env does not give lerobot: {'; '.join(problems)}. The env gives: {given}",
        )
