"""Plugin registrations: the pack's data root (no heavy imports, loading stays cheap)."""

from __future__ import annotations

from typing import Any

from embodichain_core.plugins import hookimpl

from embodichain_assets import DATA_ROOT

PROVIDER = "embodichain-assets"


@hookimpl
def embodichain_register_assets(register: Any) -> None:
    """Register the shipped data folder with ``get_data_path``."""
    register(PROVIDER, DATA_ROOT)
