"""Core test fixtures; the helpers live in :mod:`core_testlib` (unique module name)."""

import os
import sys

sys.path.insert(0, os.path.dirname(__file__))

from core_testlib import make_cfg, make_env  # noqa: E402,F401  (fixtures)
