"""What the driver says when a worker dies: which worker, which episodes, why, and what happens now.

Ray's errors (``ActorDiedError``, ``RayActorError`` and their ``RpcError`` details) are read
here and never printed as they are: :func:`death_reason` turns one into a reason in words
(killed or crashed, out of memory, its env failed to build) and :func:`worker_death_note`
into the line the driver prints.
"""

from __future__ import annotations

import re

PROG = "embodichain generate"


class GenerateError(RuntimeError):
    """A run that cannot go on for a reason the tool understands (reported in one line, no traceback)."""


def death_reason(err: BaseException, pid: int = 0) -> str:
    """Why a worker died, in words, from Ray's error (never its raw text); ``pid``: its last known process id."""
    text = str(err)
    named = re.search(r"\bpid[:=]\s*(\d+)", text)
    pid = int(named.group(1)) if named else pid
    where = f" (pid {pid})" if pid else ""
    if "creation task" in text:
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        return f"building its env failed{where}: {lines[-1] if lines else type(err).__name__}"
    if re.search(r"out of memory|\bOOM\b|memory pressure", text, re.IGNORECASE):
        return f"its process ran out of memory{where}"
    return f"its process died{where}: killed, or it crashed"


def worker_death_note(
    worker: int,
    batch: list | None,
    err: BaseException,
    restarts: int,
    limit: int,
    requeue: bool,
    gone: bool,
    pid: int = 0,
) -> str:
    """The line that says which worker died (``pid``: its last known process id), with which
    batch, and what happens now ('' for a probe of a worker already reported)."""
    if gone:
        return (
            f"worker {worker} is gone for good ({death_reason(err, pid)}; it died {restarts} time(s), "
            f"--max-restarts {limit}); the other workers take its episodes"
        )
    if batch is None:
        return ""
    episodes = ", ".join(str(k) for k in batch)
    if not requeue:
        return (
            f"worker {worker} died while running episode(s) {episodes} ({death_reason(err, pid)}); the run is stopping"
        )
    then = (
        f"Ray restarts it (restart {restarts} of {limit}) and they run again"
        if restarts <= limit
        else "they go to the other workers"
    )
    return f"worker {worker} died while running episode(s) {episodes} ({death_reason(err, pid)}); {then}"
