"""Registrations of embodichain-lerobot: lazy ``"module:attr"`` strings only, so
loading the plugin imports neither lerobot nor torch."""

from __future__ import annotations

from typing import Any

from embodichain_core.plugins import hookimpl

#: registered name -> (target, one-line description)
FUNCTORS: dict[str, tuple[str, str]] = {
    "LeRobotRecorder": (
        "embodichain_lerobot.recorder:LeRobotRecorder",
        "Record committed episodes as a LeRobot dataset (lerobot 0.4.x)",
    ),
    "AsyncLeRobotRecorder": (
        "embodichain_lerobot.async_recorder:AsyncLeRobotRecorder",
        "LeRobotRecorder that writes and encodes on a worker thread",
    ),
}


@hookimpl
def embodichain_register_functors(register: Any) -> None:
    """Register the recorders as ``dataset`` functors."""
    for name, (target, description) in FUNCTORS.items():
        register(name, target, kind="dataset", category="dataset.lerobot", description=description)


@hookimpl
def embodichain_register_commands(register: Any) -> None:
    """Register ``embodichain dataset`` and ``embodichain eval-policy``."""
    register(
        "dataset",
        "embodichain_lerobot.cli:main",
        help="Inspect, replay and view LeRobot datasets: 'info', 'preview', 'replay', 'view' PATH",
    )
    register(
        "eval-policy",
        "embodichain_lerobot.eval_cli:main",
        help="Evaluate a trained LeRobot policy (lerobot-train folder) in a task",
    )
