"""Registrations of embodichain-rl: a lazy ``"module:attr"`` string, so loading the
plugin imports neither rsl_rl, Stable-Baselines3 nor torch."""

from __future__ import annotations

from typing import Any

from embodichain_core.plugins import hookimpl


@hookimpl
def embodichain_register_commands(register: Any) -> None:
    """Register ``embodichain train-rl``."""
    register(
        "train-rl",
        "embodichain_rl.cli:main",
        help="Train a task with rsl_rl or Stable-Baselines3 PPO; --play CHECKPOINT writes an mp4",
    )
