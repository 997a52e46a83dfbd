"""Fixtures of the embodichain-tasks tests; the helpers live in ``tasks_helpers.py``
(importable: this directory is put on ``sys.path``)."""

from __future__ import annotations

import os
import sys
from typing import Any

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from tasks_helpers import embodichain_command, run_cli  # noqa: E402


@pytest.fixture
def embodichain_cli() -> Any:
    """``embodichain_cli(*args)``: run ``embodichain <args>`` in a subprocess."""

    def run(*args: str, timeout: float = 300.0) -> Any:
        return run_cli([*embodichain_command(), *args], timeout=timeout)

    return run
