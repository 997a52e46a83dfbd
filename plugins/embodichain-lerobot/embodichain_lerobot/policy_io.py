"""Load a LeRobot policy and its processors from a ``lerobot-train`` checkpoint folder.

Everything goes through lerobot's own factory functions: ``PreTrainedConfig.from_pretrained``
reads ``config.json`` (its ``type`` picks the policy), ``get_policy_class(type).from_pretrained``
loads ``model.safetensors``, and ``make_pre_post_processors(cfg, pretrained_path=...)`` loads
``policy_preprocessor.json`` / ``policy_postprocessor.json`` with their normalization
statistics. Nothing is downloaded.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

from embodichain_core.config.errors import ConfigError

__all__ = ["LoadedPolicy", "find_pretrained_dir", "load_policy", "REQUIRED_FILES"]

#: Files every pretrained-model folder written by ``lerobot-train`` (lerobot 0.4.x) holds.
REQUIRED_FILES = ("config.json", "model.safetensors", "policy_preprocessor.json", "policy_postprocessor.json")
#: Where the policy lies below a ``lerobot-train`` output folder or one of its checkpoints.
_BELOW = ("pretrained_model", "checkpoints/last/pretrained_model")


@dataclass
class LoadedPolicy:
    """A policy in eval mode with its processors.

    Attributes:
        path: the pretrained-model folder.
        policy: the ``PreTrainedPolicy``.
        preprocessor: observation batch -> normalized batch on the policy's device.
        postprocessor: policy action -> unnormalized action on the CPU.
    """

    path: Path
    policy: Any
    preprocessor: Any
    postprocessor: Any

    @property
    def config(self) -> Any:
        """The policy's ``PreTrainedConfig``."""
        return self.policy.config

    @property
    def action_dim(self) -> int:
        """The size of the policy's ``action`` output."""
        return int(self.config.output_features["action"].shape[0])


def find_pretrained_dir(path: str | Path) -> Path:
    """The pretrained-model folder ``path`` names.

    ``path`` may be the folder itself, a checkpoint folder (``.../checkpoints/005000``) or the
    ``lerobot-train`` output folder (``--output_dir``), whose ``checkpoints/last`` is used.

    Raises:
        ConfigError: ``policy`` when no folder with the files of :data:`REQUIRED_FILES` is there.
    """
    root = Path(path).expanduser()
    for candidate in (root, *(root / below for below in _BELOW)):
        if (candidate / "config.json").is_file():
            missing = [f for f in REQUIRED_FILES if not (candidate / f).is_file()]
            if missing:
                raise ConfigError(
                    "policy",
                    f"{candidate} is not a complete LeRobot pretrained-model folder: missing {', '.join(missing)}",
                )
            return candidate
    what = "does not exist" if not root.exists() else "holds no config.json"
    raise ConfigError(
        "policy",
        f"{root} {what}; give the pretrained_model folder lerobot-train writes "
        "(<output_dir>/checkpoints/last/pretrained_model) or its output_dir",
    )


def load_policy(path: str | Path, device: Optional[str] = None) -> LoadedPolicy:
    """Load the policy at ``path`` (see :func:`find_pretrained_dir`) with lerobot's factories.

    Args:
        path: the pretrained-model folder (or a folder above it).
        device: run the policy there (``"cpu"``, ``"cuda"``); default: the device it was
            trained on when available, else the one lerobot picks.

    Returns:
        The policy in eval mode and its processors; the preprocessor puts the batch on the
        policy's device.
    """
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.policies.factory import get_policy_class, make_pre_post_processors

    folder = find_pretrained_dir(path)
    cfg = PreTrainedConfig.from_pretrained(folder, cli_overrides=[f"--device={device}"] if device else [])
    cfg.pretrained_path = folder
    policy = get_policy_class(cfg.type).from_pretrained(folder, config=cfg)
    policy.eval()
    pre, post = make_pre_post_processors(
        cfg, pretrained_path=str(folder), preprocessor_overrides={"device_processor": {"device": str(cfg.device)}}
    )
    return LoadedPolicy(folder, policy, pre, post)
