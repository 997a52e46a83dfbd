"""``embodichain run-env``: run a task id or a JSON/YAML gym config.

With neither a task id nor ``--gym_config`` it runs the built-in demo scene
(:mod:`embodichain_core.demo`). CLI values override the config only when given.
Episodes run with random actions, or, when the env has ``create_demo_action_list``,
by replaying the demo action list (data generation). Dataset outputs are checked
before the env is built (:func:`~embodichain_core.cli.run_errors.preflight_outputs`).
An error while running prints its traceback and the config path of the functor that
raised it; the env is closed (datasets finalized) and the summary printed either way.
Exit codes: 0 success, 1 stopped by an error, 2 configuration error, 130 interrupted
(Ctrl-C), 143 terminated (``SIGTERM``, handled like Ctrl-C).

Example:
    $ embodichain run-env --num_envs 4 --max_episodes 8 --headless
    $ embodichain run-env --gym_config configs/push_cube.yaml --preview
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
import time
from typing import Any, Optional, Sequence

from embodichain_core.cli.run_errors import RunError, describe_error, preflight_outputs, report_error
from embodichain_core.cli.run_loops import (  # noqa: F401  (re-exported)
    RunPlan,
    RunStats,
    describe_space,
    lost_episodes,
    make_env,
    output_paths,
    preview,
    print_summary,
    run_episodes,
    written_episodes,
)
from embodichain_core.config.errors import ConfigError
from embodichain_core.gym_utils import add_env_launcher_args_to_parser, launcher_overrides
from embodichain_core.utils.suggest import did_you_mean

PROG = "embodichain run-env"
_CONFIG_EXTS = (".json", ".yaml", ".yml")


EPILOG = """
**Errors.** A configuration error (a bad key or value, an unknown task id, an unusable
dataset folder) prints one line naming the config key and exits with 2 before anything is
built. An exception raised while building or running prints its traceback, then one line
naming the functor that raised it by its config path, for example
`ValueError in functor env.events.drive_damping: ...`, and exits with 1; Ctrl-C exits with
130, and `SIGTERM` (`kill PID`, a job scheduler's stop) is handled the same way and exits
with 143. Either way the env is closed, so dataset recorders finalize (the episodes saved so far
stay loadable), and the summary is printed with a `stopped` line saying why.

**Dataset outputs.** Before the env is built, each dataset functor class that defines
`preflight(params, path)` checks its output: a dataset recorder, for example, that its
output folder is writable and has room (its keys and defaults are documented with the plugin
that provides it; for recorded datasets, datasets.md). A failed check stops the run with a
config error naming the key, such as `env.dataset.<name>.params.save_path`.
`--filter_dataset_saving` records nothing and skips the checks. An error while recording (a
disk that fills up, say) ends the run like any other: the env is closed and the episodes
saved before it stay loadable.

**Exit codes.** 0 success, 1 stopped by an error, 2 configuration error, 130 interrupted
(Ctrl-C), 143 terminated (SIGTERM).
"""


class Terminated(KeyboardInterrupt):
    """``SIGTERM`` arrived: the run stops the way a Ctrl-C stops it (env closed, summary printed)."""


#: Set when ``SIGTERM`` arrived: a library that turns any exception of a signal handler into a
#: plain ``KeyboardInterrupt`` (Ray's waits do) must not make a SIGTERM read as a Ctrl-C.
_SIGTERM_SEEN = threading.Event()


def _raise_terminated(signum: int, frame: Any) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not cut the closing short
    _SIGTERM_SEEN.set()
    raise Terminated


@contextlib.contextmanager
def sigterm_as_interrupt() -> Any:
    """Within the block (main thread only), ``SIGTERM`` raises :class:`Terminated`."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _SIGTERM_SEEN.clear()
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupt_code(err: KeyboardInterrupt) -> tuple[int, str]:
    """The exit code and the ``stopped`` reason of a Ctrl-C or a ``SIGTERM``."""
    terminated = isinstance(err, Terminated) or _SIGTERM_SEEN.is_set()
    return (143, "terminated (SIGTERM)") if terminated else (130, "interrupted (Ctrl-C)")


def build_parser() -> argparse.ArgumentParser:
    """The ``run-env`` argument parser.

    The launcher flags come from the one definition,
    :func:`embodichain_core.gym_utils.add_env_launcher_args_to_parser` (same flags,
    defaults and renderer choices as a script's); ``run-env`` adds ``TASK_ID``,
    ``--max_steps`` and ``--quiet``. Only the values given on the command line override
    the config (:func:`overrides_from_args`).

    Returns:
        The parser.
    """
    p = argparse.ArgumentParser(
        prog=PROG,
        description="Run a task or a gym config with random or demo actions.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("task", nargs="?", metavar="TASK_ID", help="gym task id (or a .json/.yaml config file)")
    add_env_launcher_args_to_parser(p)
    p.add_argument(
        "--max_steps", type=int, metavar="N", help="episode step limit, max_episode_steps (default: the config's)"
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar and no construction summary")
    return p


def overrides_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """The CLI values given, as flat loader overrides; a flag not given keeps the config's value.

    Args:
        args: a namespace parsed by :func:`build_parser`.

    Returns:
        :func:`~embodichain_core.gym_utils.launcher_overrides` (only the launcher values
        given), plus ``max_episode_steps`` from ``--max_steps`` and ``verbose=False`` from
        ``--quiet`` when given; ``--preview`` also sets ``filter_dataset_saving``.
    """
    values = launcher_overrides(args)
    if args.max_steps is not None:
        values["max_episode_steps"] = args.max_steps
    if args.quiet:
        values["verbose"] = False
    return values


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``embodichain run-env`` with ``argv``; return the exit code."""
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    try:
        with sigterm_as_interrupt():
            return _main(args)
    except ConfigError as err:
        source = _config_arg(args)
        print(f"{PROG}: config error{f' in {source}' if source else ''}: {err}", file=sys.stderr)
        return 2


def _main(args: argparse.Namespace) -> int:
    plan = prepare(args)
    if not args.preview:
        preflight_outputs(plan.cfg)  # an unusable dataset folder fails before the build
    stats = RunStats()
    started = time.perf_counter()
    try:
        env = make_env(plan)
    except KeyboardInterrupt as err:
        print(f"{PROG}: {_interrupt_code(err)[1]} while building the env", file=sys.stderr)
        return _interrupt_code(err)[0]
    except ConfigError:
        raise
    except Exception as err:
        return report_error(PROG, err, "building the env")
    stats.build_s = time.perf_counter() - started
    if args.preview:
        return _preview(env)
    code = _run(env, plan, stats, show_bar=not args.quiet and sys.stderr.isatty())
    closed = _close(env, stats)  # always: the dataset is finalized whatever stopped the run
    code = code or closed
    print_summary(plan.task_id, env, stats)
    return code


def _run(env: Any, plan: RunPlan, stats: RunStats, show_bar: bool) -> int:
    """Run the episodes; an error is reported (traceback, functor path) and ends the run."""
    try:
        run_episodes(env, plan.extras, stats, show_bar=show_bar)
        return 0
    except KeyboardInterrupt as err:
        code, stats.error = _interrupt_code(err)
        with contextlib.suppress(KeyboardInterrupt):  # a second Ctrl-C this soon: the close still runs
            print(f"{PROG}: {stats.error}; closing (committed episodes are kept)", file=sys.stderr)
        return code
    except RunError as err:
        print(f"{PROG}: {err}", file=sys.stderr)
        stats.error = str(err)
        return 1
    except Exception as err:
        stats.error = describe_error(err)
        return report_error(PROG, err, "running episodes")


def _close(env: Any, stats: RunStats) -> int:
    """Close the env, which finalizes the dataset (saved episodes stay loadable); 0 or 1."""
    manager = getattr(env.unwrapped, "dataset_manager", None)
    code, interrupted = 0, False
    try:
        env.close()
    except KeyboardInterrupt as err:  # a second Ctrl-C: stop waiting, still say what was saved
        (code, reason), interrupted = _interrupt_code(err), True
        stats.error = stats.error or reason
        print(
            f"{PROG}: {reason} again: stopped closing; the summary counts what is saved now (a dataset "
            "writer process still finishes the episodes it holds)",
            file=sys.stderr,
        )
    except Exception as err:  # e.g. a recorder that failed to finalize
        code = report_error(PROG, err, "closing the env")
        stats.error = stats.error or describe_error(err)
    if manager is not None:
        try:  # idempotent: what close() finalized (not waited for again after a second Ctrl-C)
            finalized = [] if interrupted else list(manager.finalize())
        except Exception:  # reported above
            finalized = []
        stats.data_paths = output_paths(env.unwrapped, finalized)
        stats.saved = written_episodes(env.unwrapped)
        stats.lost = lost_episodes(env.unwrapped, stats.saved)
    return code


def _preview(env: Any) -> int:
    try:
        preview(env)
        return 0
    except Exception as err:
        return report_error(PROG, err, "previewing")
    finally:
        env.close()


# -- what to run -------------------------------------------------------------------------------------
def _config_arg(args: argparse.Namespace) -> Optional[str]:
    if args.gym_config:
        return args.gym_config
    if args.task and args.task.lower().endswith(_CONFIG_EXTS):
        return args.task
    return None


def prepare(args: argparse.Namespace) -> RunPlan:
    """Resolve what to run: a config file, the task's default config, or a bare task id."""
    from embodichain_core.config.loader import load_config_file, load_gym_config, resolve_relative_paths
    from embodichain_core.plugins.builtin import DEMO_TASK_ID

    config = _config_arg(args)
    task_id = args.task if args.task != config else None
    config = config or _task_default_config(task_id)
    overrides = overrides_from_args(args)
    if not config and task_id:  # a task without a config file
        return _bare_task_plan(task_id, overrides)
    config = config or _task_default_config(DEMO_TASK_ID)  # neither a task nor a config: the demo
    if isinstance(config, (str, os.PathLike)):
        data = load_config_file(config)
        resolve_relative_paths(data, os.path.dirname(os.path.abspath(config)))
    else:
        data = dict(config)
    task_id = task_id or data.get("id")
    cfg_cls = _task_cfg_class(task_id)
    kwargs = {"cfg_cls": cfg_cls} if cfg_cls is not None else {}
    task_id, cfg, extras = load_gym_config(data, {**overrides, "id": task_id}, **kwargs)
    _check_task(task_id)
    return RunPlan(task_id, cfg, extras)


def _bare_task_plan(task_id: str, overrides: dict) -> RunPlan:
    """A task id without a config: CLI values become ``gym.make`` kwargs; simulation
    options (``--device``, ``--renderer``, ...) need the env's default cfg class."""
    from embodichain_core.config.loader import RUN_DEFAULTS, SIM_KEYS, apply_overrides
    from embodichain_core.sim.cfg import SimulationManagerCfg

    _check_task(task_id)
    extras = {**RUN_DEFAULTS, "id": task_id}
    apply_overrides(None, extras, {k: v for k, v in overrides.items() if k in RUN_DEFAULTS})
    given = {k: v for k, v in overrides.items() if k not in RUN_DEFAULTS and v is not None}
    defaults = SimulationManagerCfg()
    sim = {k: v for k, v in given.items() if k in SIM_KEYS or k == "renderer"}
    sim = {k: v for k, v in sim.items() if k == "renderer" or getattr(defaults, SIM_KEYS[k]) != v}
    if not sim:
        return RunPlan(task_id, None, extras, {k: v for k, v in given.items() if k not in SIM_KEYS})
    cls = _task_cfg_class(task_id)
    missing = cls().validate("cfg") if cls is not None else ["(no config class)"]
    if cls is None or missing:
        raise ConfigError(
            "",
            f"task {task_id!r} has no complete default config (unset: "
            f"{', '.join(m.removeprefix('cfg.') for m in missing)}); "
            f"pass --gym_config to use --{' --'.join(sim)}",
        )
    cfg = cls()
    apply_overrides(cfg, extras, given)
    return RunPlan(task_id, cfg, extras)


def _check_task(task_id: Any) -> None:
    import gymnasium as gym

    from embodichain_core.plugins import task_registry

    if not isinstance(task_id, str) or not task_id:
        raise ConfigError("id", "no task id: give TASK_ID or an 'id' in the gym config")
    if task_id not in gym.registry:
        ours = task_registry().names()
        raise ConfigError("id", f"unknown task {task_id!r}.{did_you_mean(task_id, ours or gym.registry)}")


def _task_default_config(task_id: Optional[str]) -> Any:
    """The config a task registers (its ``config=``), if any."""
    from embodichain_core.plugins import AmbiguousNameError, task_registry

    if not task_id:
        return None

    try:
        entry = task_registry().find(task_id)
    except AmbiguousNameError as err:  # several plugins provide the bare id: no silent choice
        raise ConfigError("id", str(err)) from None
    return entry.meta.get("config") if entry is not None else None


def _task_cfg_class(task_id: Any) -> Optional[type]:
    """The ``cfg_cls`` of a registered task's env class (``None`` when unknown)."""
    import gymnasium as gym

    from embodichain_core.envs.cfg import EmbodiedEnvCfg

    spec = gym.registry.get(task_id) if isinstance(task_id, str) else None
    if spec is None:
        return None
    try:
        entry = spec.entry_point
        creator = gym.envs.registration.load_env_creator(entry) if isinstance(entry, str) else entry
    except Exception:  # the import error surfaces again, with its traceback, in gym.make
        return None
    cls = getattr(creator, "cfg_cls", None)
    return cls if isinstance(cls, type) and issubclass(cls, EmbodiedEnvCfg) else None
