"""``embodichain eval-policy``: run a trained LeRobot policy in a task and report how it does.

The env is built as ``embodichain run-env`` builds it (a task id, its default config, or a
gym config; CLI values override the config only when given), with dataset recording off.
The policy is a ``lerobot-train`` pretrained-model folder. Exit codes: 0 success, 1 an
error while running, 2 a configuration error (a bad folder, task or config, or a policy
whose inputs the env does not have), 130 interrupted.

Example:
    $ embodichain eval-policy --policy outputs/act/checkpoints/last/pretrained_model \\
          --task PushCube-v1 --episodes 20 --num_envs 4 --json eval.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Optional, Sequence

from embodichain_core.config.errors import ConfigError

PROG = "embodichain eval-policy"

EPILOG = """
**Inputs.** The env's observations are named as `LeRobotRecorder` names them
(`robot/qpos` is `observation.state`, `sensor/<cam>/color` is `observation.images.<cam>`, ...),
so a policy trained on a dataset recorded from a task runs on that task as it is. An input of
the policy that the env lacks, or has with another shape, stops the run with one error listing
the policy's inputs and the env's features.

**Output.** A table of the episodes (env, success, return, length, how it ended), then the
success rate, mean return and mean length; `--json` writes the same, per episode, to a file;
`--video` writes `episode_<n>.mp4` per episode (the observation cameras side by side).

**Exit codes.** 0 success, 1 an error while running, 2 configuration error, 130 interrupted.
"""


def build_parser() -> argparse.ArgumentParser:
    """The ``eval-policy`` argument parser."""
    p = argparse.ArgumentParser(
        prog=PROG,
        description="Evaluate a trained LeRobot policy in a task.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add = p.add_argument
    add(
        "--policy",
        required=True,
        metavar="DIR",
        help="required: the lerobot-train pretrained_model folder (or its output_dir: checkpoints/last is used)",
    )
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument(
        "--task", metavar="ID", help="gym task id, with the config the task ships (this or --gym_config)"
    )
    where.add_argument(
        "--gym_config", metavar="FILE", help="JSON/YAML gym config file, EmbodiChain layout (this or --task)"
    )
    add("--episodes", type=int, required=True, metavar="N", help="required: the number of episodes to evaluate")
    add("--num_envs", type=int, metavar="K", help="parallel envs (default: the config's, at most N)")
    add("--seed", type=int, metavar="S", help="reset seed of the env and torch seed (default: the config's)")
    add("--video", metavar="DIR", help="write an mp4 per episode into this folder")
    add("--headless", action="store_true", help="run without a viewer window")
    add(
        "--viewer",
        choices=("auto", "native", "browser", "none"),
        help="watch the episodes: auto = a native window with a display, else a browser page on localhost",
    )
    add("--json", metavar="FILE", help="write the results as JSON")
    add("--max_steps", type=int, metavar="N", help="episode step limit, max_episode_steps (default: the config's)")
    add(
        "--instruction",
        metavar="TEXT",
        help="language instruction given to the policy as 'task' (default: "
        "the instruction.lang of the config's LeRobot recorder, if any)",
    )
    add("--policy_device", metavar="DEVICE", help="device of the policy (default: its own, if available)")
    add("--quiet", action="store_true", help="no progress bar and no episode table")
    return p


def _plan(args: argparse.Namespace) -> Any:
    """What to build, resolved by run-env's loader (recording off)."""
    from embodichain_core.cli import run_env
    from embodichain_core.gym_utils import GIVEN_ATTR

    given = {"filter_dataset_saving": True}
    if args.num_envs is not None:
        given["num_envs"] = min(args.num_envs, args.episodes)
    if args.seed is not None:
        given["seed"] = args.seed
    if args.headless:
        given["headless"] = True
    if args.viewer is not None:
        given["viewer"] = args.viewer  # any but none turns headless off (launcher_overrides)
    ns = argparse.Namespace(
        task=args.task, gym_config=args.gym_config or "", max_steps=args.max_steps, quiet=True, **given
    )
    setattr(ns, GIVEN_ATTR, set(given))
    plan = run_env.prepare(ns)
    if args.instruction is None:
        args.instruction = recorded_instruction(plan.cfg)
    if plan.cfg is not None and int(getattr(plan.cfg, "num_envs", 1)) > args.episodes:
        plan.cfg.num_envs = args.episodes  # no env runs an episode that is not evaluated
    return plan


def recorded_instruction(cfg: Any) -> Optional[str]:
    """The ``params.instruction.lang`` of the first dataset functor of ``cfg`` that has one."""
    for functor in (getattr(cfg, "dataset", None) or {}).values():
        lang = ((getattr(functor, "params", None) or {}).get("instruction") or {}).get("lang")
        if isinstance(lang, str):
            return lang
    return None


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``embodichain eval-policy`` with ``argv``; return the exit code."""
    args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    try:
        if args.episodes < 1:
            raise ConfigError("episodes", f"--episodes must be at least 1, got {args.episodes}")
        return _run(args)
    except ConfigError as err:
        print(f"{PROG}: config error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


def _run(args: argparse.Namespace) -> int:
    from embodichain_core.cli.run_env import make_env
    from embodichain_core.cli.run_errors import report_error
    from embodichain_lerobot.policy_io import load_policy

    try:
        loaded = load_policy(args.policy, args.policy_device)
    except ConfigError:
        raise
    except Exception as err:  # a folder lerobot cannot read (another lerobot version, a broken file)
        return report_error(PROG, err, f"loading the policy from {args.policy}")
    plan = _plan(args)
    try:
        env = make_env(plan)
    except ConfigError:
        raise
    except Exception as err:
        return report_error(PROG, err, "building the env")
    try:
        result = _evaluate(env, loaded, args)
    except (ConfigError, KeyboardInterrupt):
        raise
    except Exception as err:
        return report_error(PROG, err, "evaluating")
    finally:
        env.close()
    if not args.quiet:
        print_report(result, loaded.path, plan.task_id)
    if args.json:
        write_json(result, Path(args.json), loaded.path, plan.task_id, args)
    return 0


def _evaluate(env: Any, loaded: Any, args: argparse.Namespace) -> Any:
    import torch
    from tqdm import tqdm

    from embodichain_lerobot.eval_policy import evaluate

    if args.seed is not None:
        torch.manual_seed(args.seed)
    video = Path(args.video) if args.video else None
    if video is not None:
        video.mkdir(parents=True, exist_ok=True)
    successes = 0

    with tqdm(total=args.episodes, unit="ep", desc="eval-policy", disable=args.quiet, file=sys.stderr) as bar:

        def progress(episode: Any) -> None:
            nonlocal successes
            successes += bool(episode.success)
            bar.set_postfix(success=f"{successes}/{bar.n + 1}", refresh=False)
            bar.update(1)

        return evaluate(
            env, loaded, args.episodes, seed=args.seed, video_dir=video, progress=progress, instruction=args.instruction
        )


def print_report(result: Any, policy: Path, task_id: str) -> None:
    """The episode table and the summary, on stdout."""
    print(f"policy        {policy}")
    print(f"task          {task_id}")
    print(f"{'episode':>7}  {'env':>3}  {'success':<7}  {'return':>10}  {'length':>6}  end")
    for e in result.episodes:
        end = "terminated" if e.terminated else "truncated"
        print(
            f"{e.episode:>7}  {e.env_id:>3}  {'yes' if e.success else 'no':<7}  {e.episode_return:>10.3f}  {e.length:>6}  {end}"
            + (f"  {e.video}" if e.video else "")
        )
    print(f"episodes      {len(result.episodes)}")
    print(f"success rate  {result.success_rate:.3f}")
    print(f"mean return   {result.mean_return:.3f}")
    print(f"mean length   {result.mean_length:.1f}")
    print(f"env steps     {result.env_steps} in {result.seconds:.1f} s")


def write_json(result: Any, path: Path, policy: Path, task_id: str, args: argparse.Namespace) -> None:
    """The results, with what was evaluated, as JSON at ``path``."""
    data = {
        "policy": str(policy),
        "task": task_id,
        "gym_config": args.gym_config,
        "seed": args.seed,
        "instruction": args.instruction,
        **result.to_dict(),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    if not args.quiet:
        print(f"json          {path}")
