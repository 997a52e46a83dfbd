"""Progress of ``embodichain generate``: the tqdm bar on a terminal, plain lines elsewhere.

On a terminal (``stderr`` is one) the bar is drawn. When the output goes to a file, a CI
log or a scheduler (no terminal to draw a bar on), :class:`PlainProgress` prints a plain
line to ``stdout`` at the first saved episode, then at most every ``spec.progress_every``
seconds, and when the last episode is saved::

    generate: 12/100 episode(s) saved (12%), 0.42 episode(s)/s, ETA 3m29s

``--quiet`` prints neither.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any, TextIO

from embodichain_ray.spec import GenerateSpec


def format_duration(seconds: float) -> str:
    """``42s``, ``3m29s`` or ``2h05m``."""
    s = int(round(max(seconds, 0.0)))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


class PlainProgress:
    """A tqdm-like counter (``update``, ``set_postfix_str``) that prints plain progress lines.

    Args:
        total: episodes to save.
        initial: episodes already saved when the run started (a resumed run); not in the rate.
        every: seconds between two lines (a line also comes at the first and the last episode).
        out: where the lines go (``stdout`` when ``None``).
        clock: the time source (seconds).
    """

    def __init__(
        self,
        total: int,
        initial: int = 0,
        every: float = 30.0,
        out: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.total, self.initial, self.n, self.every = total, initial, initial, every
        self._out, self._clock = out, clock
        self._start = clock()
        self._last: float | None = None

    def update(self, n: int = 1) -> None:
        """``n`` more episodes saved; prints a line when one is due."""
        if n <= 0:
            return
        self.n += n
        now = self._clock()
        if self._last is None or now - self._last >= self.every or self.n >= self.total:
            self._last = now
            print(self.line(now), file=self._out or sys.stdout, flush=True)

    def line(self, now: float) -> str:
        """The progress line at time ``now``."""
        done = self.n - self.initial
        elapsed = max(now - self._start, 1e-9)
        rate = done / elapsed
        left = max(self.total - self.n, 0)
        eta = format_duration(left / rate) if rate > 0 and left else ("done" if not left else "unknown")
        percent = 100.0 * self.n / self.total if self.total else 100.0
        return f"generate: {self.n}/{self.total} episode(s) saved ({percent:.0f}%), {rate:.2f} episode(s)/s, ETA {eta}"

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        """The bar's speed note: not part of the plain lines."""


@contextlib.contextmanager
def progress(spec: GenerateSpec, desc: str, initial: int = 0) -> Iterator[Any]:
    """The run's progress counter: the bar (``spec.show_bar``), plain lines
    (``spec.progress_every`` > 0) or nothing."""
    if spec.show_bar or spec.progress_every <= 0:
        from tqdm import tqdm

        with tqdm(total=spec.episodes, initial=initial, unit="ep", desc=desc, disable=not spec.show_bar) as bar:
            yield bar
        return
    yield PlainProgress(spec.episodes, initial, spec.progress_every)
