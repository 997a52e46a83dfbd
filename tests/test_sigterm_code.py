"""A SIGTERM reads as a SIGTERM (exit 143) even when a library re-raises it as a plain
KeyboardInterrupt, as Ray's waits do with an exception raised by a signal handler."""

from __future__ import annotations

import os
import signal

import pytest

from embodichain_core.cli.run_env import Terminated, _interrupt_code, sigterm_as_interrupt


def _library_wait() -> None:
    """What Ray's wait does: the handler's exception becomes a fresh KeyboardInterrupt."""
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        signal.sigtimedwait([], 0.1)  # let the handler run here
    except KeyboardInterrupt:
        raise KeyboardInterrupt() from None


def test_a_sigterm_relabelled_as_keyboard_interrupt_still_exits_143() -> None:
    with sigterm_as_interrupt(), pytest.raises(KeyboardInterrupt) as err:
        _library_wait()
    assert not isinstance(err.value, Terminated)  # the library lost the type
    assert _interrupt_code(err.value) == (143, "terminated (SIGTERM)")


def test_a_ctrl_c_after_an_earlier_sigterm_block_is_a_ctrl_c() -> None:
    with sigterm_as_interrupt(), pytest.raises(KeyboardInterrupt):
        _library_wait()
    with sigterm_as_interrupt():  # a new run: the earlier SIGTERM does not count
        assert _interrupt_code(KeyboardInterrupt()) == (130, "interrupted (Ctrl-C)")
        assert _interrupt_code(Terminated()) == (143, "terminated (SIGTERM)")
