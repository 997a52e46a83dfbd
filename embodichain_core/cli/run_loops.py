"""The loops and reports of ``embodichain run-env``: random-action episodes, scripted
demo rounds (data generation with retries), the preview and the end-of-run summary."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Optional

from embodichain_core.cli.run_errors import RunError


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
    failed: int = 0
    saved: Optional[int] = None
    lost: int = 0  # finished episodes handed to a recorder that were not saved (its writer failed)
    recording: bool = False
    env_steps: int = 0
    discarded: int = 0
    build_s: float = 0.0
    run_s: float = 0.0
    data_paths: Optional[list] = None
    error: Optional[str] = None  # what stopped the run early


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


def _host_flags(n: int, *values: Any) -> Any:
    """(len(values), n) bool flags on the host, read from the env's device in one copy (a
    scalar flag stands for every env)."""
    import torch

    device = next((v.device for v in values if isinstance(v, torch.Tensor)), None)
    rows = [torch.as_tensor(v, device=device).reshape(-1).to(torch.bool).expand(n) for v in values]
    return torch.stack(rows).cpu()


def _done_success(terminated: Any, truncated: Any, info: dict, n: int) -> tuple[Any, Any]:
    """Per-env ``(done, success)`` of a step, on the host."""
    flags = _host_flags(n, terminated, truncated, info["success"])
    return flags[0] | flags[1], flags[2]


def run_episodes(env: Any, extras: dict, stats: RunStats, show_bar: bool = False) -> None:
    """Run until ``extras["max_episodes"]`` episodes are done (saved, when a dataset
    recorder is configured); scripted demos replace random actions when the env has
    ``create_demo_action_list``."""
    from tqdm import tqdm

    base = env.unwrapped
    target = int(extras.get("max_episodes") or 1)
    started = time.perf_counter()
    stats.recording = getattr(base, "dataset_manager", None) is not None
    try:
        with tqdm(total=target, unit="ep", disable=not show_bar, desc=extras.get("id") or "run-env") as bar:
            env.reset(options={"save_data": False})
            while _progress(base, stats) < target:
                before = _progress(base, stats)
                if hasattr(base, "create_demo_action_list"):
                    _demo_round(env, int(extras.get("demo_max_attempts") or 1), stats)
                else:
                    _random_step(env, stats)
                bar.update(min(_progress(base, stats), target) - min(before, target))
                bar.set_postfix(success=stats.successes, refresh=False)
    finally:
        stats.run_s = time.perf_counter() - started
        stats.saved = _saved(base)


def _saved(base: Any) -> Optional[int]:
    manager = getattr(base, "dataset_manager", None)
    return None if manager is None else int(manager.committed_episodes)


def written_episodes(base: Any) -> Optional[int]:
    """Episodes the recorders report as written (``saved_episodes``; after ``finalize`` that
    includes queued ones), else the episodes committed to them; ``None`` without recorders."""
    manager = getattr(base, "dataset_manager", None)
    if manager is None:
        return None
    reported = [getattr(e.func, "saved_episodes", None) for e in manager.entries.values()]
    counts = [c for c in reported if isinstance(c, int) and not isinstance(c, bool)]
    return max(counts) if counts else int(manager.committed_episodes)


def lost_episodes(base: Any, saved: Optional[int]) -> int:
    """Finished episodes handed to the recorders but not saved: what they report
    (``lost_episodes``), else the committed episodes beyond ``saved``."""
    manager = getattr(base, "dataset_manager", None)
    if manager is None:
        return 0
    reported = [getattr(e.func, "lost_episodes", None) for e in manager.entries.values()]
    counts = [c for c in reported if isinstance(c, int) and not isinstance(c, bool)]
    return max(counts) if counts else max(int(manager.committed_episodes) - (saved or 0), 0)


def output_paths(base: Any, finalized: list) -> list:
    """What ``finalize`` returned, plus the existing ``dataset_path`` of recorders whose
    ``finalize`` failed (their saved episodes are still there)."""
    import os

    manager = getattr(base, "dataset_manager", None)
    paths = [p for p in finalized if p]
    for entry in manager.entries.values() if manager is not None else ():
        path = getattr(entry.func, "dataset_path", None)
        if path is not None and os.path.isdir(path) and str(path) not in {str(p) for p in paths}:
            paths.append(path)
    return paths


def _progress(base: Any, stats: RunStats) -> int:
    """Saved episodes when recording, else finished episodes."""
    saved = _saved(base)
    return stats.episodes if saved is None else saved


def _random_step(env: Any, stats: RunStats) -> None:
    """One step with a random action; count the episodes it finished."""
    n = env.unwrapped.num_envs
    _, _, terminated, truncated, info = env.step(_as_torch(env.action_space.sample()))
    stats.env_steps += n
    done, success = _done_success(terminated, truncated, info, n)
    if done.any():
        stats.episodes += int(done.sum())
        stats.successes += int((success & done).sum())


def _demo_round(env: Any, max_attempts: int, stats: RunStats) -> None:
    """One episode per env from the demo action list, retried up to ``max_attempts`` times.

    Successful rows are committed (all rows when the dataset keeps failed episodes);
    an attempt where no row succeeds is discarded with ``reset(save_data=False)`` and
    retried. After ``max_attempts`` failed attempts the run stops with an error.
    """
    import torch

    base = env.unwrapped
    n = base.num_envs
    manager = getattr(base, "dataset_manager", None)
    keep_failed = manager is not None and manager.save_failed_episodes
    for attempt in range(1, max_attempts + 1):
        success, ended = _replay_demo(env, stats)  # counts the episodes that ended early
        stats.episodes += int((~ended).sum())
        stats.successes += int((success & ~ended).sum())
        if success.any() or keep_failed:
            open_ids = torch.nonzero(~ended).flatten()
            if len(open_ids):
                env.reset(options={"reset_ids": open_ids})  # commit boundary of the unfinished rows
            if ended.any():  # rows that ended early were committed by the auto-reset
                env.reset(options={"reset_ids": torch.nonzero(ended).flatten(), "save_data": False})
            stats.failed += int((~success).sum())
            return
        env.reset(options={"save_data": False})
        stats.discarded += n
        stats.failed += n
    raise RunError(f"the scripted demo failed in every env in {max_attempts} attempt(s) in a row")


def _replay_demo(env: Any, stats: RunStats) -> tuple[Any, Any]:
    """Step the demo action list; return per-env success and whether the episode ended early.

    An episode that ends early is counted (``stats.episodes``, ``stats.successes``) at the step
    that ended it: the env's auto-reset has committed it then, so a Ctrl-C right after still
    finds it in the counts."""
    import torch

    base = env.unwrapped
    n = base.num_envs
    success = torch.zeros(n, dtype=torch.bool)
    ended = torch.zeros(n, dtype=torch.bool)
    for action in base.create_demo_action_list() or []:
        _, _, terminated, truncated, info = env.step(_as_torch(action))
        stats.env_steps += n
        done, succeeded = _done_success(terminated, truncated, info, n)
        done &= ~ended
        success |= done & succeeded
        ended |= done
        stats.episodes += int(done.sum())
        stats.successes += int((done & success).sum())
        if ended.all():
            return success, ended
    success |= ~ended & _host_flags(n, base.is_task_success())[0]
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
    """The end-of-run summary: episodes, saved, success rate, throughput, time, data, and
    what stopped the run when an error did."""
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
    outside = getattr(env.unwrapped, "out_of_space_actions", None)
    if outside is not None:
        lines.append(f"  actions      {outside} env-step(s) outside the action space (clipped)")
    lines += _dataset_lines(stats)
    if stats.discarded:
        lines.append(f"  discarded    {stats.discarded} failed demo episode(s)")
    if paths:
        lines += ["  data         " + paths[0], *("               " + p for p in paths[1:])]
    else:
        lines.append(
            "  data         " + ("none (no dataset recorder)" if stats.data_paths is None else "nothing saved")
        )
    if stats.error:
        lines.append(f"  stopped      early: {stats.error}")
    print("\n".join(lines))


def _dataset_lines(stats: RunStats) -> list[str]:
    """What the recorders hold: saved episodes (as the recorders count them on disk), the demo
    episodes that failed, and committed episodes that were lost (each on its own line)."""
    if stats.saved is None:
        return []
    lines = [f"  saved        {stats.saved} episode(s)"]
    if stats.failed:
        lines.append(f"  failed       {stats.failed} demo episode(s) did not succeed")
    if stats.lost > 0:
        lines.append(f"  lost         {stats.lost} finished episode(s) were not saved (the error above says why)")
    return lines
