"""``embodichain run-env``: run a task id or a JSON/YAML gym config.

With neither a task id nor ``--gym_config`` it runs the built-in demo scene
(:mod:`embodichain_core.demo`). CLI values override the config only when given.
Episodes run with random actions, or, when the env has ``create_demo_action_list``,
by replaying the demo action list (data generation). The run ends with a summary.
Exit codes: 0 success, 2 configuration error.

Example:
    $ embodichain run-env --num_envs 4 --max_episodes 8 --headless
    $ embodichain run-env --gym_config configs/push_cube.yaml --preview
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean

PROG = "embodichain run-env"
_CONFIG_EXTS = (".json", ".yaml", ".yml")


@dataclass
class RunPlan:
    """What to build: the task id, its cfg (``None``: the task's own default), the
    run-level extras and further ``gym.make`` kwargs (cfg fields, for a bare task id)."""

    task_id: str
    cfg: Any = None
    extras: dict = field(default_factory=dict)
    make_kwargs: dict = field(default_factory=dict)


@dataclass
class RunStats:
    """Counters of a run."""

    episodes: int = 0
    successes: int = 0
    env_steps: int = 0
    discarded: int = 0
    build_s: float = 0.0
    run_s: float = 0.0
    data_paths: Optional[list] = None


def build_parser() -> argparse.ArgumentParser:
    """The ``run-env`` argument parser; every override defaults to ``None`` (not given)."""
    p = argparse.ArgumentParser(prog=PROG, description="Run a task or a gym config with random or demo actions.")
    p.add_argument("task", nargs="?", metavar="TASK_ID", help="gym task id (or a .json/.yaml config file)")
    p.add_argument("--gym_config", metavar="FILE", help="JSON/YAML gym config (EmbodiChain layout)")
    p.add_argument("--num_envs", type=int, help="parallel environments")
    p.add_argument("--headless", action="store_true", default=None, help="no viewer window")
    p.add_argument("--device", help="simulation device (sim_cfg.sim_device)")
    p.add_argument("--renderer", help="render_cfg.renderer")
    p.add_argument("--max_episodes", type=int, help="episodes to run, summed over envs")
    p.add_argument("--max_steps", type=int, help="episode step limit (max_episode_steps)")
    p.add_argument("--seed", type=int, help="RNG seed")
    p.add_argument("--preview", action="store_true", help="build, reset, step once, describe the spaces, exit")
    p.add_argument("--filter_visual_rand", action="store_true", default=None, help="drop visual randomization")
    p.add_argument("--filter_dataset_saving", action="store_true", default=None, help="record no dataset")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no construction summary")
    return p


def overrides_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """The CLI values as flat loader overrides (``None`` = not given, config value kept)."""
    return {
        "num_envs": args.num_envs, "headless": args.headless, "device": args.device,
        "renderer": args.renderer, "max_episodes": args.max_episodes, "max_episode_steps": args.max_steps,
        "seed": args.seed, "filter_visual_rand": args.filter_visual_rand,
        "filter_dataset_saving": True if args.preview else args.filter_dataset_saving,
        "verbose": False if args.quiet else None,
    }


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``embodichain run-env`` with ``argv``; return the exit code."""
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    try:
        return _main(args)
    except ConfigError as err:
        source = _config_arg(args)
        print(f"{PROG}: config error{f' in {source}' if source else ''}: {err}", file=sys.stderr)
        return 2


def _main(args: argparse.Namespace) -> int:
    plan = prepare(args)
    stats, env = RunStats(), None
    started = time.perf_counter()
    try:
        env = make_env(plan)
        stats.build_s = time.perf_counter() - started
        if args.preview:
            preview(env)
            return 0
        run_episodes(env, plan.extras, stats, show_bar=not args.quiet and sys.stderr.isatty())
    finally:
        if env is not None:
            env.close()
    manager = getattr(env.unwrapped, "dataset_manager", None)
    stats.data_paths = list(manager.finalize()) if manager is not None else None
    print_summary(plan.task_id, env, stats)
    return 0


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
    from embodichain_core.demo import DEMO_CONFIG, register_demo_task
    from embodichain_core.plugins import load_plugins

    load_plugins()
    register_demo_task()
    config = _config_arg(args)
    task_id = args.task if args.task != config else None
    config = config or _task_default_config(task_id) or (None if task_id else str(DEMO_CONFIG))
    overrides = overrides_from_args(args)
    if config is None:
        return _bare_task_plan(task_id, overrides)
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
    if missing:
        raise ConfigError("", f"task {task_id!r} has no complete default config (unset: "
                              f"{', '.join(m.removeprefix('cfg.') for m in missing)}); "
                              f"pass --gym_config to use --{' --'.join(sim)}")
    cfg = cls()
    apply_overrides(cfg, extras, given)
    return RunPlan(task_id, cfg, extras)


def _check_task(task_id: Any) -> None:
    import gymnasium as gym

    from embodichain_core.envs.registration import REGISTERED_ENVS
    from embodichain_core.plugins import task_registry

    if not isinstance(task_id, str) or not task_id:
        raise ConfigError("id", "no task id: give TASK_ID or an 'id' in the gym config")
    if task_id not in gym.registry:
        ours = sorted({*task_registry().names(), *REGISTERED_ENVS})
        raise ConfigError("id", f"unknown task {task_id!r}.{did_you_mean(task_id, ours or gym.registry)}")


def _task_default_config(task_id: Optional[str]) -> Any:
    """The config a task ships: the demo's, or a plugin task's ``config=`` meta."""
    from embodichain_core.demo import DEMO_CONFIG, DEMO_TASK_ID
    from embodichain_core.plugins import task_registry

    if not task_id:
        return None
    if task_id == DEMO_TASK_ID:
        return str(DEMO_CONFIG)
    entry = task_registry().find(task_id)
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


def make_env(plan: RunPlan) -> Any:
    """``gymnasium.make(id, cfg=cfg)``, or ``gymnasium.make(id, **cli_values)`` without a cfg."""
    import gymnasium as gym

    if plan.cfg is None:
        return gym.make(plan.task_id, **plan.make_kwargs)
    return gym.make(plan.task_id, cfg=plan.cfg)


# -- running -----------------------------------------------------------------------------------------
def _as_torch(value: Any) -> Any:
    import torch

    if isinstance(value, dict):
        return {k: _as_torch(v) for k, v in value.items()}
    return torch.as_tensor(value)


def _flags(value: Any, n: int) -> Any:
    import torch

    return torch.as_tensor(value, dtype=torch.bool).reshape(-1).expand(n)


def run_episodes(env: Any, extras: dict, stats: RunStats, show_bar: bool = False) -> None:
    """Run ``extras["max_episodes"]`` episodes (demo replay when the env offers one)."""
    from tqdm import tqdm

    base = env.unwrapped
    target = int(extras.get("max_episodes") or 1)
    started = time.perf_counter()
    with tqdm(total=target, unit="ep", disable=not show_bar, desc=extras.get("id") or "run-env") as bar:
        env.reset(options={"save_data": False})
        while stats.episodes < target:
            before = stats.episodes
            if hasattr(base, "create_demo_action_list"):
                _demo_round(env, int(extras.get("demo_max_attempts") or 1), stats)
            else:
                _random_step(env, stats)
            bar.update(min(stats.episodes, target) - min(before, target))
            bar.set_postfix(success=stats.successes, refresh=False)
    stats.run_s = time.perf_counter() - started


def _random_step(env: Any, stats: RunStats) -> None:
    """One step with a random action; count the episodes it finished."""
    n = env.unwrapped.num_envs
    _, _, terminated, truncated, info = env.step(_as_torch(env.action_space.sample()))
    stats.env_steps += n
    done = _flags(terminated, n) | _flags(truncated, n)
    if done.any():
        stats.episodes += int(done.sum())
        stats.successes += int((_flags(info["success"], n) & done).sum())


def _demo_round(env: Any, max_attempts: int, stats: RunStats) -> None:
    """One episode per env from the demo action list, retried up to ``max_attempts`` times.

    An attempt where no env succeeds is discarded (``reset(save_data=False)``) unless
    the dataset keeps failed episodes; the last failed attempt is counted as failed.
    """
    import torch

    base = env.unwrapped
    n = base.num_envs
    manager = getattr(base, "dataset_manager", None)
    keep_failed = manager is not None and manager.save_failed_episodes
    for attempt in range(1, max_attempts + 1):
        success, ended = _replay_demo(env, stats)
        if success.any() or keep_failed or attempt == max_attempts:
            open_ids = torch.nonzero(~ended).flatten()
            if len(open_ids):
                env.reset(options={"reset_ids": open_ids})  # commit boundary of the unfinished rows
            if ended.any():
                env.reset(options={"reset_ids": torch.nonzero(ended).flatten(), "save_data": False})
            stats.episodes += n
            stats.successes += int(success.sum())
            if not success.any() and not keep_failed:
                warnings.warn(f"demo failed in all {max_attempts} attempt(s)", RuntimeWarning, stacklevel=2)
            return
        env.reset(options={"save_data": False})
        stats.discarded += n


def _replay_demo(env: Any, stats: RunStats) -> tuple[Any, Any]:
    """Step the demo action list; return per-env success and whether the episode ended early."""
    import torch

    base = env.unwrapped
    n = base.num_envs
    success = torch.zeros(n, dtype=torch.bool)
    ended = torch.zeros(n, dtype=torch.bool)
    for action in base.create_demo_action_list() or []:
        _, _, terminated, truncated, info = env.step(_as_torch(action))
        stats.env_steps += n
        done = (_flags(terminated, n) | _flags(truncated, n)) & ~ended
        success |= done & _flags(info["success"], n)
        ended |= done
        if ended.all():
            return success, ended
    success |= ~ended & _flags(base.is_task_success(), n)
    return success, ended


# -- output ------------------------------------------------------------------------------------------
def describe_space(space: Any, indent: str = "  ") -> list[str]:
    """Indented lines describing a (nested) gymnasium space."""
    spaces = getattr(space, "spaces", None)
    if isinstance(spaces, dict):
        lines = []
        for key, sub in spaces.items():
            inner = describe_space(sub, indent + "  ")
            if len(inner) == 1 and not isinstance(getattr(sub, "spaces", None), dict):
                lines.append(f"{indent}{key}: {inner[0].strip()}")
            else:
                lines += [f"{indent}{key}:", *inner]
        return lines
    shape, dtype = getattr(space, "shape", None), getattr(space, "dtype", None)
    return [f"{indent}{type(space).__name__} shape={tuple(shape) if shape is not None else None} dtype={dtype}"]


def preview(env: Any) -> None:
    """Reset, step once with a random action and print the spaces and the info keys."""
    base = env.unwrapped
    env.reset()
    _, _, _, _, info = env.step(_as_torch(env.action_space.sample()))
    print(f"Preview of {type(base).__name__} ({base.num_envs} env(s))")
    print("observation space (per env):", *describe_space(base.single_observation_space), sep="\n")
    print("action space (per env):", *describe_space(base.single_action_space), sep="\n")
    print("info keys after one step:", ", ".join(sorted(map(str, info))))


def print_summary(task_id: str, env: Any, stats: RunStats) -> None:
    """The end-of-run summary: episodes, success rate, throughput, time, data."""
    rate = 100.0 * stats.successes / stats.episodes if stats.episodes else 0.0
    speed = stats.env_steps / stats.run_s if stats.run_s > 0 else 0.0
    paths = [str(p) for p in stats.data_paths or [] if p]
    lines = [
        f"run-env summary: {task_id}",
        f"  episodes     {stats.episodes} ({env.unwrapped.num_envs} env(s))",
        f"  successes    {stats.successes}/{stats.episodes} ({rate:.1f}%)",
        f"  env steps    {stats.env_steps} ({speed:.1f} env-steps/s)",
        f"  wall time    {stats.build_s + stats.run_s:.2f} s (build {stats.build_s:.2f} s, run {stats.run_s:.2f} s)",
    ]
    if stats.discarded:
        lines.append(f"  discarded    {stats.discarded} failed demo episode(s)")
    if paths:
        lines += ["  data         " + paths[0], *("               " + p for p in paths[1:])]
    else:
        lines.append("  data         " + ("none (no dataset recorder)" if stats.data_paths is None else "nothing saved"))
    print("\n".join(lines))
