"""How ``embodichain run-env`` fails: output checks before the build, error reports after.

* :func:`preflight_outputs` runs before the env is built: every dataset functor
  class with a ``preflight(params, path)`` classmethod checks its output (a dataset
  recorder: its output folder is writable and has room). It raises a
  :class:`~embodichain_core.config.errors.ConfigError` naming the config key.
* :func:`report_error` prints an error raised while building or running: the
  traceback, then one line naming the functor that raised it (its config path, e.g.
  ``env.events.drive_damping``, from
  :func:`~embodichain_core.managers.manager_base.functor_path_of`) and the error.
* :class:`~embodichain_core.errors.RunError` is an expected way for a run to end (message
  only, no traceback, whether it stops the run or the closing of the env).
"""

from __future__ import annotations

import inspect
import sys
import traceback
from typing import Any

from embodichain_core.config.errors import ConfigError, join_path
from embodichain_core.errors import RunError
from embodichain_core.managers.cfg import DatasetFunctorCfg
from embodichain_core.managers.manager_base import functor_path_of, iter_section, resolve_func

#: Exit code of a run stopped by an error (configuration errors exit with 2, Ctrl-C with 130).
EXIT_ERROR = 1
EXIT_CONFIG = 2


def preflight_outputs(cfg: Any) -> None:
    """Let each dataset functor check its output before the env is built.

    A dataset functor class may define ``preflight(params: dict, path: str)``; it gets
    the functor's params and config path (``env.dataset.<name>``) and raises a
    ``ConfigError`` when it could not write (no-op without a cfg, a dataset section,
    or with ``filter_dataset_saving``).

    Raises:
        ConfigError: a functor reported an unusable output (its message names the key).
    """
    if cfg is None or getattr(cfg, "filter_dataset_saving", False):
        return
    for name, fcfg in iter_section(getattr(cfg, "dataset", None), DatasetFunctorCfg, "env.dataset"):
        where = join_path("env.dataset", name)
        func = resolve_func(fcfg.func, "dataset", where)
        hook = getattr(func, "preflight", None)
        if inspect.isclass(func) and callable(hook):
            hook(dict(fcfg.params or {}), where)


def describe_error(err: BaseException) -> str:
    """One line: where the error was raised (the functor's config path) and what it says."""
    path = functor_path_of(err)
    where = f" in functor {path}" if path else ""
    kind = "config error" if isinstance(err, ConfigError) else type(err).__name__
    return f"{kind}{where}: {err}"


def report_error(prog: str, err: BaseException, during: str = "") -> int:
    """Print ``err`` to stderr and return the exit code.

    Configuration errors get one line (exit 2), a :class:`~embodichain_core.errors.RunError`
    one line (exit 1); anything else gets its traceback
    (which ends with the functor note, when a functor raised it) and then one line
    naming the functor (exit 1).

    Args:
        prog: the command, prefixed to the line.
        err: the error.
        during: what was going on (``"building the env"``), for the line.
    """
    when = f" while {during}" if during else ""
    if isinstance(err, ConfigError) and functor_path_of(err) is None:
        print(f"{prog}: {describe_error(err)}", file=sys.stderr)
        return EXIT_CONFIG
    if isinstance(err, RunError):  # understood: its message says it all
        print(f"{prog}: stopped{when}: {err}", file=sys.stderr)
        return EXIT_ERROR
    traceback.print_exception(err, file=sys.stderr)
    print(f"{prog}: stopped by an error{when}: {describe_error(err)}", file=sys.stderr)
    return EXIT_CONFIG if isinstance(err, ConfigError) else EXIT_ERROR
