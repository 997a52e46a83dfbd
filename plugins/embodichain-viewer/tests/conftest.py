"""Fixtures of the embodichain-viewer tests (helpers in ``viewer_helpers.py``).

Nothing here touches the user's environment: Hugging Face caches point into a temporary
folder, viewers listen on free localhost ports, and the native viewer runs on a private
Xvfb display started by the test.
"""

from __future__ import annotations

import os
import sys
import tempfile

_CACHE = tempfile.mkdtemp(prefix="embodichain-viewer-hf-")
os.environ.setdefault("HF_HUB_OFFLINE", "1")
os.environ.setdefault("HF_HOME", _CACHE)
os.environ.setdefault("HF_DATASETS_CACHE", os.path.join(_CACHE, "datasets"))
sys.path.append(os.path.dirname(__file__))

from typing import Any, Iterator  # noqa: E402

import pytest  # noqa: E402

from embodichain_viewer import session as viewer_session  # noqa: E402


@pytest.fixture
def every_step_published(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Publish a snapshot after every step (the viewer normally skips those within 1/30 s)."""
    monkeypatch.setattr(viewer_session, "PUBLISH_HZ", float("inf"))
    yield


def pytest_configure(config: Any) -> None:
    config.addinivalue_line("filterwarnings", "ignore:Conversion of an array with ndim > 0:DeprecationWarning")
    config.addinivalue_line("filterwarnings", "ignore:The video decoding and encoding capabilities:UserWarning")
