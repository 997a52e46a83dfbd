"""Imitation learning from our demonstrations, end to end: generate, train, evaluate.

``python -m embodichain_lerobot.il_pipeline --out DIR`` runs, and prints before each step,
the three commands a user would type:

1. ``embodichain generate``: scripted demos of the task on Ray workers, one merged
   dataset (``DIR/demos``), from a copy of the gym config (``DIR/config.json``) without
   its cameras (``--cameras`` keeps them, for a visuomotor policy) and without videos;
   the config's recorder must list ``environment_state`` (the task observations a
   state-based policy needs);
2. ``lerobot-train``: an ACT policy on ``observation.state`` + ``observation.environment_state``
   (``DIR/train``), a checkpoint every ``--save_freq`` steps;
3. ``embodichain eval-policy``: every checkpoint on ``--eval_episodes`` new episodes
   (``--eval_seed``; the episode seeds are checked against the training demos' seeds:
   none may be shared), results in ``DIR/eval/<step>.json``.

It then writes ``DIR/results.json`` (the commands, the data, each checkpoint's success
rate) and ``DIR/success_curve.png``. A step whose output exists is not run again, so an
interrupted pipeline resumes. ACT (not Diffusion): one forward pass per action chunk
(Diffusion denoises for each), it trains in far fewer steps on a CPU, and chunked actions
suit the scripted demos' smooth, unimodal trajectories (no VAE needed).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any, Optional, Sequence

__all__ = ["main", "plot_curve", "state_config"]


def _main_job() -> Optional[Path]:
    """The main job's config shipped by ``embodichain-tasks`` (``None`` when it is not installed)."""
    spec = importlib.util.find_spec("embodichain_tasks")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations))) / "configs" / "main_job.json"


#: The default ``--config``: PickFork-v1's main job (``embodichain-tasks``).
MAIN_JOB = _main_job()
#: ACT settings for a state-only policy on a CPU (lerobot-train flags).
ACT_FLAGS = (
    "--policy.type=act",
    "--policy.chunk_size=20",
    "--policy.n_action_steps=10",
    "--policy.dim_model=256",
    "--policy.dim_feedforward=1024",
    "--policy.n_encoder_layers=2",
    "--policy.n_decoder_layers=1",
    "--policy.use_vae=false",
    "--policy.optimizer_lr=1e-4",
    "--policy.push_to_hub=false",
)


def state_config(source: Path, cameras: bool) -> dict[str, Any]:
    """The gym config to generate and evaluate with: no cameras (unless ``cameras``), no videos.

    Raises:
        ValueError: the config has no LeRobot recorder listing ``environment_state``.
    """
    data = json.loads(source.read_text(encoding="utf-8"))
    recorders = [f for f in (data.get("env", {}).get("dataset") or {}).values() if "Recorder" in str(f.get("func"))]
    if not recorders or not (recorders[0].get("params") or {}).get("environment_state"):
        raise ValueError(f"{source}: its LeRobot recorder must list params.environment_state (see docs/datasets.md)")
    if not cameras:
        data["sensor"] = []
        recorders[0]["params"]["use_videos"] = False
    return data


def _run(cmd: list[str], log: list[str], env: Optional[dict] = None) -> None:
    line = " ".join(shlex.quote(c) for c in cmd)
    log.append(line)
    print(f"\n$ {line}", flush=True)
    subprocess.run(cmd, check=True, env=env)


def _bin(name: str) -> str:
    return str(Path(sys.executable).with_name(name))


def _checkpoints(train_dir: Path) -> list[tuple[int, Path]]:
    """``(step, pretrained_model folder)`` of every saved checkpoint, by step."""
    found = []
    for path in (train_dir / "checkpoints").glob("[0-9]*"):
        if (path / "pretrained_model" / "config.json").is_file():
            found.append((int(path.name), path / "pretrained_model"))
    return sorted(found)


def _seeds(dataset: Path) -> set[int]:
    from embodichain_lerobot.reading import read_sidecar

    return {int(r["episode_seed"]) for r in read_sidecar(dataset) if r.get("episode_seed") is not None}


def plot_curve(points: Sequence[tuple[int, float]], path: Path, title: str) -> Path:
    """A success-rate-over-training-steps PNG (Pillow; no plotting library needed)."""
    from PIL import Image, ImageDraw

    w, h, m = 640, 400, 60
    img = Image.new("RGB", (w, h), "white")
    d = ImageDraw.Draw(img)
    d.rectangle([m, m // 2, w - m // 2, h - m], outline="black")
    last = max((s for s, _ in points), default=1) or 1
    for frac in (0.0, 0.25, 0.5, 0.75, 1.0):
        y = h - m - frac * (h - 1.5 * m)
        d.line([m - 4, y, m, y], fill="black")
        d.text((8, y - 6), f"{frac:.2f}", fill="black")
    xy = [(m + s / last * (w - 1.5 * m), h - m - r * (h - 1.5 * m)) for s, r in points]
    if len(xy) > 1:
        d.line(xy, fill="blue", width=2)
    for (x, y), (s, r) in zip(xy, points):
        d.ellipse([x - 3, y - 3, x + 3, y + 3], fill="blue")
        d.text((x - 10, h - m + 6), str(s), fill="black")
    d.text((m, 8), title, fill="black")
    d.text((w // 2 - 40, h - 22), "training step", fill="black")
    img.save(path)
    return path


def build_parser() -> argparse.ArgumentParser:
    """The pipeline's options (defaults: the documented PickFork-v1 run)."""
    p = argparse.ArgumentParser(prog="python -m embodichain_lerobot.il_pipeline", description=__doc__.splitlines()[0])
    add = p.add_argument
    add("--config", type=Path, default=MAIN_JOB, help="gym config with a LeRobot recorder (default: the main job)")
    add("--out", type=Path, required=True, help="output folder (config, demos, train, eval, results)")
    add("--demos", type=int, default=100, help="demonstrations to generate (default 100)")
    add("--workers", type=int, default=2, help="Ray workers of embodichain generate (default 2)")
    add("--num_envs", type=int, default=2, help="envs per worker, and of eval-policy (default 2)")
    add("--seed", type=int, default=0, help="generate's run seed (default 0)")
    add("--steps", type=int, default=5000, help="lerobot-train steps (default 5000)")
    add("--save_freq", type=int, default=1000, help="steps between checkpoints (default 1000)")
    add("--batch_size", type=int, default=64, help="lerobot-train batch size (default 64)")
    add("--eval_episodes", type=int, default=50, help="episodes per evaluated checkpoint (default 50)")
    add("--eval_seed", type=int, default=1_000_000, help="eval-policy's reset seed (default 1000000)")
    add("--cameras", action="store_true", help="keep the config's cameras (a visuomotor policy; use a GPU)")
    add("--device", default="cpu", help="lerobot-train's policy device (default cpu)")
    return p


def _generate(args: argparse.Namespace, config: Path, demos: Path, log: list[str]) -> None:
    if demos.exists():
        print(f"{demos} exists: not generated again", flush=True)
        log.append(f"# {demos} existed")
        return
    cmd = [_bin("embodichain"), "generate", "--gym_config", str(config), "--episodes", str(args.demos)]
    cmd += ["--workers", str(args.workers), "--num_envs", str(args.num_envs), "--seed", str(args.seed)]
    _run([*cmd, "--output", str(demos), "--quiet"], log)


def _train(args: argparse.Namespace, demos: Path, train: Path, log: list[str]) -> None:
    if any(step >= args.steps for step, _ in _checkpoints(train)):
        print(f"{train} has its last checkpoint: not trained again", flush=True)
        return
    cmd = [_bin("lerobot-train"), f"--dataset.repo_id=local/{demos.name}", f"--dataset.root={demos}", *ACT_FLAGS]
    cmd += [f"--policy.device={args.device}", f"--output_dir={train}", f"--steps={args.steps}"]
    cmd += [f"--save_freq={args.save_freq}", f"--batch_size={args.batch_size}", "--num_workers=0"]
    cmd += ["--log_freq=100", "--wandb.enable=false", f"--seed={args.seed}"]
    if args.cameras:
        cmd.append("--policy.pretrained_backbone_weights=null")  # nothing is downloaded
    if train.exists():  # lerobot-train refuses an existing output_dir; resuming is lerobot's own flag
        raise SystemExit(
            f"{train} holds an unfinished training: resume it with lerobot-train "
            f"--config_path={train}/checkpoints/last/pretrained_model/train_config.json --resume=true, "
            "or delete it"
        )
    _run(cmd, log)


def _evaluate(args: argparse.Namespace, config: Path, train: Path, out: Path, log: list[str]) -> list[dict]:
    rows = []
    for step, policy in _checkpoints(train):
        result = out / "eval" / f"{step:06d}.json"
        if not result.is_file():
            cmd = [_bin("embodichain"), "eval-policy", "--policy", str(policy), "--gym_config", str(config)]
            cmd += ["--episodes", str(args.eval_episodes), "--num_envs", str(args.num_envs)]
            _run([*cmd, "--seed", str(args.eval_seed), "--json", str(result), "--quiet"], log)
        data = json.loads(result.read_text(encoding="utf-8"))
        rows.append(
            {
                "step": step,
                "success_rate": data["success_rate"],
                "episodes": data["num_episodes"],
                "mean_length": data["mean_length"],
                "seeds": [e.get("episode_seed") for e in data["episodes"]],
            }
        )
    return rows


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the pipeline; 0 when it ran to the end."""
    from embodichain_lerobot.reading import go_offline

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.config is None:
        parser.error("--config is required: embodichain-tasks (the default PickFork-v1 main job) is not installed")
    go_offline()  # lerobot-train and eval-policy read local folders only
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    config = out / "config.json"
    config.write_text(json.dumps(state_config(args.config, args.cameras), indent=1), encoding="utf-8")
    log: list[str] = []
    demos, train = out / "demos", out / "train"
    _generate(args, config, demos, log)
    _train(args, demos, train, log)
    rows = _evaluate(args, config, train, out, log)
    trained = _seeds(demos)
    shared = sorted({s for r in rows for s in r.pop("seeds") if s in trained})
    if shared:
        raise SystemExit(f"eval episodes share seeds with the training demos: {shared[:5]}")
    results = {
        "config": str(args.config),
        "demos": {"path": str(demos), "episodes": len(trained), "seed": args.seed},
        "policy": {"type": "act", "flags": list(ACT_FLAGS), "steps": args.steps, "batch_size": args.batch_size},
        "eval": {"episodes": args.eval_episodes, "seed": args.eval_seed, "seeds_shared_with_training": 0},
        "checkpoints": rows,
        "commands": log,
    }
    (out / "results.json").write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    curve = plot_curve(
        [(r["step"], r["success_rate"]) for r in rows],
        out / "success_curve.png",
        f"{json.loads(config.read_text())['id']}: eval success rate ({args.eval_episodes} episodes)",
    )
    for r in rows:
        print(f"step {r['step']:>7}  success {r['success_rate']:.2f}  ({r['episodes']} episodes)")
    print(f"results {out / 'results.json'}\ncurve   {curve}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
