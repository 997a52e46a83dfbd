"""Imitation learning from our demonstrations, end to end: generate, train, validate, test.

``python -m embodichain_lerobot.il_pipeline --out DIR [--policy state|camera]`` runs, and
prints before each step, the commands a user would type:

1. ``embodichain generate``: scripted demos of the task on Ray workers, one merged dataset
   (``DIR/demos``), from a copy of the gym config (``DIR/config.json``) made for the recipe
   (:mod:`embodichain_lerobot.il_recipes`: the state recipe renders no camera, the camera
   recipe only the cameras named by ``--cameras`` and records no object pose);
2. ``lerobot-train``: lerobot's ACT on what the recipe reads (``DIR/train``), a checkpoint
   every ``--save_freq`` steps;
3. ``embodichain eval-policy`` of every checkpoint on ``--val_episodes`` validation episodes
   (``--val_seed``), results in ``DIR/eval/val_<step>.json``, in the training config or in
   ``--eval_config`` (its recipe copy ``DIR/eval_config.json``);
4. ``embodichain eval-policy`` of the checkpoint with the best validation rate on
   ``--test_episodes`` test episodes (``--test_seed``), ``DIR/eval/test_<step>.json``: the
   reported rate, from episodes that chose nothing.

Training, validation and test episodes never share a seed (checked from the datasets'
``meta/embodichain_episodes.jsonl`` and the eval files; the run stops if one does). It writes
``DIR/results.json`` (commands, wall time of each stage, every validation rate and the test
rate with their 95% Wilson intervals, the test episodes one by one) and
``DIR/success_curve.png``. A step whose output exists is not run again, so an interrupted
pipeline resumes; a training whose last checkpoint is short of ``--steps`` (interrupted, or
run again with more steps) is resumed from that checkpoint by lerobot-train.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shlex
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Optional, Sequence

from embodichain_lerobot.il_recipes import CHUNK_SIZE, LR_SCHEDULES, POLICIES, pipeline_config, train_flags
from embodichain_lerobot.il_stats import choose_checkpoint, format_rate, rate_summary

__all__ = ["main", "build_parser", "MAIN_JOB", "STATE_CONFIG", "CAMERA_CONFIG"]


def _tasks_config(name: str) -> Optional[Path]:
    """A config shipped by ``embodichain-tasks`` (``None`` when it is not installed)."""
    spec = importlib.util.find_spec("embodichain_tasks")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations))) / "configs" / name


#: PickFork-v1's data-generation job (what ``make run`` records).
MAIN_JOB = _tasks_config("main_job.json")
#: The state recipe's default ``--config``: that job with the fork's centre of mass in
#: ``environment_state`` beside its pose (the six fork meshes differ in where it lies).
STATE_CONFIG = _tasks_config("pick_fork_state.json")
#: The camera recipe's default ``--config``: the same job with a 96x96 policy camera.
CAMERA_CONFIG = _tasks_config("pick_fork_camera.json")


def build_parser() -> argparse.ArgumentParser:
    """The pipeline's options (defaults: the documented PickFork-v1 runs)."""
    p = argparse.ArgumentParser(prog="python -m embodichain_lerobot.il_pipeline", description=__doc__.splitlines()[0])
    add = p.add_argument
    add("--out", type=Path, required=True, help="output folder (config, demos, train, eval, results)")
    add("--policy", choices=POLICIES, default="state", help="what the policy reads (default: state)")
    add(
        "--config",
        type=Path,
        help="gym config with a LeRobot recorder, a path or the name of one embodichain-tasks ships "
        "(e.g. open_drawer_record.json; default: the recipe's PickFork-v1 config)",
    )
    add(
        "--eval_config",
        type=Path,
        help="evaluate (validation and test) in this gym config instead of --config, a path or a "
        "shipped name (e.g. demonstrations from perturbed starts, evaluated on the task as it is)",
    )
    add("--cameras", nargs="+", default=["policy_cam"], help="camera recipe: the cameras it reads (default policy_cam)")
    add("--demos", type=int, default=100, help="demonstrations to generate (default 100)")
    add("--workers", type=int, default=2, help="Ray workers of embodichain generate (default 2)")
    add("--num_envs", type=int, default=2, help="envs per worker, and of eval-policy (default 2)")
    add("--seed", type=int, default=0, help="generate's run seed and lerobot-train's seed (default 0)")
    add("--steps", type=int, default=5000, help="lerobot-train steps (default 5000)")
    add("--save_freq", type=int, default=1000, help="steps between checkpoints (default 1000)")
    add(
        "--lr_schedule",
        choices=LR_SCHEDULES,
        default="constant",
        help="state recipe: constant (lerobot's ACT preset) or cosine (decayed to 1e-6 by --steps)",
    )
    add(
        "--chunk_size",
        type=int,
        default=CHUNK_SIZE,
        help=f"actions ACT predicts per chunk (default {CHUNK_SIZE}: 0.8 s at 25 Hz)",
    )
    add("--batch_size", type=int, default=64, help="lerobot-train batch size (default 64)")
    add("--num_workers", type=int, default=0, help="lerobot-train data loader processes (default 0)")
    add("--val_episodes", type=int, default=50, help="validation episodes per checkpoint (default 50)")
    add("--val_seed", type=int, default=1_000_000, help="validation reset seed (default 1000000)")
    add("--val_from", type=int, default=0, help="validate the checkpoints from this step on (default: all)")
    add("--test_episodes", type=int, default=100, help="test episodes of the chosen checkpoint (default 100)")
    add("--test_seed", type=int, default=2_000_000, help="test reset seed (default 2000000)")
    add("--max_steps", type=int, help="step limit of evaluated episodes (default: the config's max_episode_steps)")
    add("--device", default="cpu", help="lerobot-train's policy device (default cpu)")
    add(
        "--no_visual_randomization",
        action="store_true",
        help="generate and evaluate without the config's visual randomization (env.filter_visual_rand)",
    )
    return p


def _check_args(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    counts = "demos steps save_freq chunk_size batch_size val_episodes test_episodes workers num_envs max_steps"
    for name in counts.split():
        if getattr(args, name) is not None and getattr(args, name) < 1:
            parser.error(f"--{name} must be at least 1, got {getattr(args, name)}")
    if args.config is None:
        args.config = CAMERA_CONFIG if args.policy == "camera" else STATE_CONFIG
    if args.config is None:
        parser.error("--config is required: embodichain-tasks (the default PickFork-v1 configs) is not installed")
    args.config = _resolve_config(parser, args.config)
    if args.eval_config is not None:
        args.eval_config = _resolve_config(parser, args.eval_config, "--eval_config")
    if args.policy == "camera" and args.lr_schedule != "constant":
        parser.error("--lr_schedule: the camera recipe trains at a constant rate (its backbone has its own)")


def _resolve_config(parser: argparse.ArgumentParser, config: Path, flag: str = "--config") -> Path:
    """``config`` itself when it is a file, else the embodichain-tasks config of that name."""
    if config.is_file():
        return config
    shipped = _tasks_config(config.name) if config.parent == Path(".") else None
    if shipped is not None and shipped.is_file():
        return shipped
    folder = _tasks_config("")
    names = sorted(p.name for p in folder.glob("*.json")) if folder is not None and folder.is_dir() else []
    parser.error(
        f"{flag}: no file {str(config)!r}"
        + (f"; the configs embodichain-tasks ships: {', '.join(names)}" if names else "")
    )


def _run(cmd: list[str], log: list[str]) -> None:
    line = " ".join(shlex.quote(c) for c in cmd)
    log.append(line)
    print(f"\n$ {line}", flush=True)
    subprocess.run(cmd, check=True)


def _bin(name: str) -> str:
    return str(Path(sys.executable).with_name(name))


def _checkpoints(train_dir: Path) -> list[tuple[int, Path]]:
    """``(step, pretrained_model folder)`` of every saved checkpoint, by step."""
    found = []
    for path in (train_dir / "checkpoints").glob("[0-9]*"):
        if (path / "pretrained_model" / "config.json").is_file():
            found.append((int(path.name), path / "pretrained_model"))
    return sorted(found)


def _train_seeds(dataset: Path) -> set[int]:
    from embodichain_lerobot.reading import read_sidecar

    return {int(r["episode_seed"]) for r in read_sidecar(dataset) if r.get("episode_seed") is not None}


class _Stages:
    """Runs the stages, timing each, and keeps the commands for ``results.json``."""

    def __init__(self, args: argparse.Namespace, out: Path):
        self.args, self.out = args, out
        self.config, self.demos, self.train = out / "config.json", out / "demos", out / "train"
        #: the config validation and test run in (``--eval_config``, else the training one)
        self.eval_config = out / "eval_config.json" if args.eval_config is not None else self.config
        self.log: list[str] = []
        self.seconds: dict[str, float] = {}

    def timed(self, stage: str, fn: Any, *a: Any) -> Any:
        start = time.monotonic()
        try:
            return fn(*a)
        finally:
            self.seconds[stage] = round(self.seconds.get(stage, 0.0) + time.monotonic() - start, 1)

    def generate(self) -> None:
        a = self.args
        if self.demos.exists():
            print(f"{self.demos} exists: not generated again", flush=True)
            return
        cmd = [_bin("embodichain"), "generate", "--gym_config", str(self.config), "--episodes", str(a.demos)]
        cmd += ["--workers", str(a.workers), "--num_envs", str(a.num_envs), "--seed", str(a.seed)]
        _run([*cmd, "--output", str(self.demos), "--quiet"], self.log)

    def train_policy(self) -> None:
        a = self.args
        if any(step >= a.steps for step, _ in _checkpoints(self.train)):
            print(f"{self.train} has its last checkpoint: not trained again", flush=True)
            return
        last = self.train / "checkpoints" / "last" / "pretrained_model" / "train_config.json"
        if last.is_file():  # a shorter or interrupted run: lerobot-train resumes it up to --steps
            cmd = [_bin("lerobot-train"), f"--config_path={last}", "--resume=true", f"--steps={a.steps}"]
            _run([*cmd, f"--save_freq={a.save_freq}"], self.log)
            return
        if self.train.exists():  # lerobot-train refuses an existing output_dir
            raise SystemExit(f"{self.train} holds a training without a checkpoint to resume from: delete it")
        cmd = [_bin("lerobot-train"), f"--dataset.repo_id=local/{self.demos.name}", f"--dataset.root={self.demos}"]
        cmd += [
            *train_flags(a.policy, a.lr_schedule, a.steps, a.chunk_size),
            f"--policy.device={a.device}",
            f"--output_dir={self.train}",
        ]
        cmd += [f"--steps={a.steps}", f"--save_freq={a.save_freq}", f"--batch_size={a.batch_size}"]
        cmd += [f"--num_workers={a.num_workers}", "--log_freq=100", "--wandb.enable=false", f"--seed={a.seed}"]
        _run(cmd, self.log)

    def evaluate(self, policy: Path, split: str, step: int, episodes: int, seed: int) -> dict[str, Any]:
        """One eval-policy run (skipped when its JSON exists); its rate summary."""
        result = self.out / "eval" / f"{split}_{step:06d}.json"
        if not result.is_file():
            cmd = [_bin("embodichain"), "eval-policy", "--policy", str(policy), "--gym_config", str(self.eval_config)]
            cmd += ["--episodes", str(episodes), "--num_envs", str(self.args.num_envs), "--headless"]
            cmd += ["--max_steps", str(self.args.max_steps)] if self.args.max_steps else []
            _run([*cmd, "--seed", str(seed), "--json", str(result), "--quiet"], self.log)
        data = json.loads(result.read_text(encoding="utf-8"))
        return {"step": step, "json": str(result), **rate_summary(data["episodes"])}


def _check_seeds(trained: set[int], validation: list[dict], test: dict) -> dict[str, int]:
    """Stop when a validation or test episode reuses a training seed, or test a validation one."""
    val = {r["seed"] for row in validation for r in row["per_episode"]}
    tst = {r["seed"] for r in test["per_episode"]}
    shared = {"validation_training": len(val & trained), "test_training": len(tst & trained)}
    shared["test_validation"] = len(tst & val)
    if any(shared.values()):
        raise SystemExit(f"evaluation episodes share seeds with other splits: {shared}")
    return shared


def _results(stages: _Stages, validation: list[dict], test: dict, shared: dict, trained: set, policy: Path) -> dict:
    a = stages.args
    return {
        "recipe": a.policy,
        "config": str(a.config),
        "eval_config": str(a.eval_config or a.config),
        "visual_randomization": not a.no_visual_randomization,
        "cameras": list(a.cameras) if a.policy == "camera" else [],
        "demos": {"path": str(stages.demos), "episodes": len(trained), "seed": a.seed},
        "policy": {
            "type": "act",
            "flags": list(train_flags(a.policy, a.lr_schedule, a.steps, a.chunk_size)),
            "steps": a.steps,
            "batch_size": a.batch_size,
        },
        "validation": {
            "episodes": a.val_episodes,
            "seed": a.val_seed,
            "from_step": a.val_from,
            "max_steps": a.max_steps,
        },
        "test_split": {"episodes": a.test_episodes, "seed": a.test_seed, "max_steps": a.max_steps},
        "seeds_shared": shared,
        "seconds": stages.seconds,
        "checkpoints": [{k: v for k, v in r.items() if k != "per_episode"} for r in validation],
        "chosen_step": test["step"],
        "chosen_policy": str(policy),
        "test": test,
        "commands": stages.log,
    }


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the pipeline; 0 when it ran to the end."""
    from embodichain_lerobot.il_plots import plot_success_curve
    from embodichain_lerobot.reading import go_offline

    parser = build_parser()
    args = parser.parse_args(argv)
    _check_args(parser, args)
    try:
        configs = [pipeline_config(c, args.policy, args.cameras) for c in (args.config, args.eval_config) if c]
    except ValueError as err:
        parser.error(str(err))
    for config in configs if args.no_visual_randomization else ():
        config.setdefault("env", {})["filter_visual_rand"] = True
    config = configs[0]
    go_offline()  # lerobot-train and eval-policy read local folders only
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    stages = _Stages(args, out)
    for path, data in zip((stages.config, stages.eval_config), configs):
        path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    stages.timed("generate", stages.generate)
    stages.timed("train", stages.train_policy)
    ckpts = [(s, p) for s, p in _checkpoints(stages.train) if s >= args.val_from]
    if not ckpts:
        raise SystemExit(f"no checkpoint at step {args.val_from} or later in {stages.train / 'checkpoints'}")
    validation = [
        stages.timed("validate", stages.evaluate, p, "val", s, args.val_episodes, args.val_seed) for s, p in ckpts
    ]
    chosen = choose_checkpoint(validation)
    policy = dict(ckpts)[chosen["step"]]
    test = stages.timed("test", stages.evaluate, policy, "test", chosen["step"], args.test_episodes, args.test_seed)
    trained = _train_seeds(stages.demos)
    results = _results(stages, validation, test, _check_seeds(trained, validation, test), trained, policy)
    (out / "results.json").write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    curve = plot_success_curve(validation, test, out / "success_curve.png", f"{config['id']} ({args.policy} policy)")
    for r in validation:
        print(f"step {r['step']:>7}  validation {format_rate(r)}")
    print(f"chosen step {test['step']}: test {format_rate(test)}")
    print(f"results {out / 'results.json'}\ncurve   {curve}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
