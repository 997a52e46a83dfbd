"""``embodichain train-rl``: train a task with rsl_rl or Stable-Baselines3 PPO, or play a checkpoint.

Examples:
    $ embodichain train-rl --task PushCube-v1 --library rsl_rl --num_envs 64 --steps 2000000 --out outputs/rl
    $ embodichain train-rl --task PushCube-v1 --library sb3 --num_envs 16 --steps 200000 --out outputs/sb3
    $ embodichain train-rl --play outputs/rl/model_1302.pt --video outputs/rl/play.mp4
    $ embodichain train-rl --play outputs/rl/model_1302.pt --viewer browser
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Optional, Sequence

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``train-rl`` flags."""
    parser = argparse.ArgumentParser(prog="embodichain train-rl", description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="PushCube-v1", help="task id (default PushCube-v1)")
    parser.add_argument("--library", choices=("rsl_rl", "sb3"), default="rsl_rl", help="RL library (default rsl_rl)")
    parser.add_argument("--num_envs", type=int, default=64, help="envs simulated together (default 64)")
    parser.add_argument("--steps", type=int, default=1_000_000, help="env steps of all envs (default 1e6)")
    parser.add_argument("--seed", type=int, default=0, help="env and torch seed (default 0)")
    parser.add_argument("--out", default="outputs/train_rl", help="output directory (default outputs/train_rl)")
    parser.add_argument("--max_episode_steps", type=int, default=0, help="episode limit; 0 keeps the task's")
    parser.add_argument(
        "--play",
        metavar="CHECKPOINT",
        help="run this checkpoint (model_*.pt or *.zip) instead of training, and write an mp4",
    )
    parser.add_argument("--video", help="mp4 path for --play (default: play.mp4 next to the checkpoint)")
    parser.add_argument("--episodes", type=int, default=1, help="episodes for --play (default 1)")
    parser.add_argument(
        "--viewer",
        choices=("auto", "native", "browser", "none"),
        help="with --play: watch the episodes (auto: a native window with a display, else a browser page)",
    )
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Train (or ``--play``); print where the outputs are."""
    args = build_parser().parse_args(argv)
    if args.num_envs < 1 or args.steps < 1 or args.episodes < 1:
        print("error: --num_envs, --steps and --episodes must be >= 1")
        return 2
    if args.play:
        from embodichain_rl.play import play

        checkpoint = Path(args.play)
        video = Path(args.video) if args.video else checkpoint.parent / "play.mp4"
        from embodichain_core.viewing import force_viewer

        with force_viewer(args.viewer):
            play(checkpoint, video, episodes=args.episodes, seed=args.seed)
        return 0
    out = Path(args.out)
    if args.library == "rsl_rl":
        from embodichain_rl import train_rsl_rl as trainer
    else:
        from embodichain_rl import train_sb3 as trainer  # type: ignore[no-redef]
    checkpoint = trainer.train(
        args.task, args.num_envs, args.steps, args.seed, out, max_episode_steps=args.max_episode_steps
    )
    print(f"checkpoint: {checkpoint}; curve: {out / 'curve.csv'}; play it: embodichain train-rl --play {checkpoint}")
    return 0
