"""Errors shared by the core and the plugins that need nothing else imported (cheap to import).

:class:`RunError` is how a run ends for a reason the tool understands: the command line
(``run-env``) prints its message alone, without a traceback, so the message itself says what
happened, what is kept and what to do next.
"""

from __future__ import annotations


class RunError(RuntimeError):
    """A run cannot go on for a known reason; reported without a traceback."""
