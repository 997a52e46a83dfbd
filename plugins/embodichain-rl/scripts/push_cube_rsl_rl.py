"""PushCube-v1 with rsl_rl PPO: train, plot the learning curve, evaluate the final policy.

Writes to ``--out``: rsl_rl's checkpoints and tensorboard events, ``curve.csv``,
``curve.png`` and ``result.json``: the final policy's success rate and mean return over
``--eval_envs`` new episodes, with its mean action (``deterministic``) and with sampled
actions as in training (``sampled``).

Example (the run the docs quote):
    $ python plugins/embodichain-rl/scripts/push_cube_rsl_rl.py --num_envs 64 --steps 3000000 \\
        --out outputs/rl_push_cube
    $ python plugins/embodichain-rl/scripts/push_cube_rsl_rl.py --evaluate_only outputs/rl_push_cube/model_1953.pt
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from embodichain_rl.evaluate import evaluate
from embodichain_rl.outputs import plot_curve
from embodichain_rl.train_rsl_rl import train


def main() -> int:
    """Train (unless ``--evaluate_only``), plot, evaluate, print the result."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--num_envs", type=int, default=64)
    parser.add_argument("--steps", type=int, default=3_000_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--eval_envs", type=int, default=100)
    parser.add_argument("--out", default="outputs/rl_push_cube")
    parser.add_argument("--evaluate_only", metavar="CHECKPOINT", help="skip training; evaluate this checkpoint")
    args = parser.parse_args()
    if args.evaluate_only:
        checkpoint = Path(args.evaluate_only)
        out = checkpoint.parent
    else:
        out = Path(args.out)
        checkpoint = train("PushCube-v1", args.num_envs, args.steps, args.seed, out)
    plot_curve(out / "curve.csv", out / "curve.png", "rsl_rl PPO, PushCube-v1")
    result = {
        "checkpoint": str(checkpoint),
        "deterministic": evaluate(checkpoint, num_envs=args.eval_envs),
        "sampled": evaluate(checkpoint, num_envs=args.eval_envs, deterministic=False),
    }
    (out / "result.json").write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
