"""Registrations of embodichain-ray: a lazy ``"module:attr"`` string, so loading the
plugin imports neither Ray nor torch."""

from __future__ import annotations

from typing import Any

from embodichain_core.plugins import hookimpl


@hookimpl
def embodichain_register_commands(register: Any) -> None:
    """Register ``embodichain generate``."""
    register(
        "generate",
        "embodichain_ray.cli:main",
        help="Generate N scripted episodes on Ray workers into one merged LeRobot dataset",
    )
