"""Load and check a generation run's config, before any worker starts.

The config is loaded exactly as ``embodichain run-env`` loads it (its parser and
:func:`~embodichain_core.cli.run_env.prepare`), so a bad config fails with the same
:class:`~embodichain_core.config.errors.ConfigError` naming its key. On top of that a
generation run needs a task with a scripted demo (``create_demo_action_list``) and
exactly one ``LeRobotRecorder`` (or ``AsyncLeRobotRecorder``) in the config's ``dataset`` section: each worker points
that recorder's ``save_path`` at its own shard folder.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from embodichain_core.cli.run_loops import RunPlan
from embodichain_core.config.errors import ConfigError
from embodichain_ray.spec import GenerateSpec, parse_run_env_args, run_env_argv

#: Only the synchronous recorder: an episode is published when the reset that commits it returns.
RECORDER_CLASS = "embodichain_lerobot.recorder:LeRobotRecorder"


@dataclass
class GeneratePlan:
    """A loaded run: the ``run-env`` plan, the recorder's config name and the retry policy.

    Attributes:
        run: what to build (task id, cfg, extras).
        recorder: the name of the dataset functor in ``cfg.dataset``.
        max_attempts: attempts per episode (``demo_max_attempts``, at least 1).
        keep_failed: the recorder saves failed episodes too (then nothing is retried).
    """

    run: RunPlan
    recorder: str
    max_attempts: int
    keep_failed: bool


def load_plan(spec: GenerateSpec, save_path: Path | None = None) -> GeneratePlan:
    """Load the run's config with its recorder's ``save_path`` at ``save_path`` (a worker's
    folder) or, for the driver's checks, at ``spec.shards``.

    Raises:
        ConfigError: the config is invalid (the same errors as ``run-env``), the task has
            no scripted demo, or the dataset section has no single ``LeRobotRecorder``.
    """
    from embodichain_core.cli.run_env import prepare

    run = prepare(parse_run_env_args(run_env_argv(spec)))
    if run.cfg is None:
        raise ConfigError("", f"task {run.task_id!r} needs a gym config with a dataset section: pass --gym_config")
    _check_demo(run.task_id)
    name, fcfg = _recorder(run.cfg)
    fcfg.params = dict(fcfg.params or {})
    fcfg.params["save_path"] = str(save_path if save_path is not None else spec.shards)
    attempts = int(run.extras.get("demo_max_attempts") or 1)
    return GeneratePlan(run, name, max(attempts, 1), bool(getattr(fcfg, "save_failed_episodes", False)))


def check_plan(spec: GenerateSpec) -> GeneratePlan:
    """:func:`load_plan` for the driver, plus every check the env runs at build (values,
    ranges, functor params, one worker's memory) and the recorder's check of the shards folder.

    Raises:
        ConfigError: as :func:`load_plan`, a bad value, or the shards folder is not writable.
    """
    from embodichain_core.cli.run_errors import preflight_outputs

    plan = load_plan(spec)
    plan.run.cfg.validate()  # what the env checks first when it builds, so no worker has to fail on it
    preflight_outputs(plan.run.cfg)
    return plan


def _check_demo(task_id: str) -> None:
    import gymnasium as gym

    entry = gym.registry[task_id].entry_point
    creator = gym.envs.registration.load_env_creator(entry) if isinstance(entry, str) else entry
    if not callable(getattr(creator, "create_demo_action_list", None)):
        raise ConfigError(
            "id",
            f"task {task_id!r} has no scripted demo (create_demo_action_list): "
            "embodichain generate records scripted demos only",
        )


def _recorder(cfg: Any) -> tuple[str, Any]:
    """The one ``LeRobotRecorder`` (or ``AsyncLeRobotRecorder``) entry of ``cfg.dataset``."""
    from embodichain_lerobot.recorder import LeRobotRecorder

    from embodichain_core.managers.cfg import DatasetFunctorCfg
    from embodichain_core.managers.manager_base import iter_section, resolve_func

    found: list[tuple[str, Any]] = []
    others: list[tuple[str, Any]] = []
    for name, fcfg in iter_section(getattr(cfg, "dataset", None), DatasetFunctorCfg, "env.dataset"):
        func = resolve_func(fcfg.func, "dataset", f"env.dataset.{name}")
        ours = inspect.isclass(func) and issubclass(func, LeRobotRecorder)  # or AsyncLeRobotRecorder
        (found if ours else others).append((name, fcfg))
    if len(found) != 1 or others:
        names = ", ".join(n for n, _ in found + others) or "none"
        raise ConfigError(
            "env.dataset",
            f"embodichain generate needs exactly one dataset functor, a "
            f"LeRobotRecorder or AsyncLeRobotRecorder (the workers record shards with it); found: {names}",
        )
    return found[0]
