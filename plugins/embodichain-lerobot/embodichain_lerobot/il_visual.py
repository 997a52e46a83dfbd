"""Does visual randomization matter? Two camera policies, each evaluated in two scenes.

``python -m embodichain_lerobot.il_visual --out DIR [pipeline options]`` runs the camera
pipeline (:mod:`embodichain_lerobot.il_pipeline`) twice on the same task and seeds, once with
the config's visual randomization (``DIR/randomized``) and once without it
(``DIR/plain``, ``env.filter_visual_rand``), then evaluates each chosen checkpoint on the same
test seeds in

* the **nominal** scene: the config's own materials, light and camera pose (no visual
  randomization), and
* a **shifted** scene (:func:`shifted_scene`): values no training episode saw: table colours
  darker than the randomization's range and no texture, a dimmer blue-tinted light, and each
  policy camera moved by up to 2 cm (its look-at target by up to 3 cm).

It writes ``DIR/table.json`` (the 2x2 rates with 95% Wilson intervals, every episode) and
``DIR/table.png`` (:func:`~embodichain_lerobot.il_plots.plot_rate_table`) and prints the table. Physical randomization (fork pose, mesh, mass) stays on everywhere.
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
from pathlib import Path
from typing import Any, Optional, Sequence

from embodichain_lerobot.il_plots import plot_rate_table
from embodichain_lerobot.il_stats import format_rate, rate_summary

__all__ = ["SHIFT", "nominal_scene", "shifted_scene", "main"]

#: The shifted scene's ranges, outside what the randomized training data saw (the shipped
#: PickFork-v1 configs draw table colours in [0.2, 1], light intensity in [15, 30] and light
#: colour in [0.7, 1] per channel, and never move the camera).
SHIFT: dict[str, Any] = {
    "table_color_range": [[0.03, 0.03, 0.03], [0.15, 0.15, 0.15]],
    "light_intensity_range": [6.0, 10.0],
    "light_color_range": [[0.45, 0.5, 0.85], [0.55, 0.6, 1.0]],
    "camera_eye_range": [[-0.02, -0.02, -0.02], [0.02, 0.02, 0.02]],
    "camera_target_range": [[-0.03, -0.03, 0.0], [0.03, 0.03, 0.0]],
}


def _visual_event(cfg: dict[str, Any]) -> bool:
    from embodichain_core.plugins import is_visual_randomization

    return isinstance(cfg.get("func"), str) and is_visual_randomization(cfg["func"])


def nominal_scene(data: dict[str, Any]) -> dict[str, Any]:
    """The config without its visual randomization (``env.filter_visual_rand``)."""
    out = copy.deepcopy(data)
    out.setdefault("env", {})["filter_visual_rand"] = True
    return out


def _uid_of(data: dict[str, Any], func: str, default: str) -> str:
    for event in ((data.get("env") or {}).get("events") or {}).values():
        if event.get("func") == func:
            return str((event.get("params") or {}).get("entity_cfg", {}).get("uid", default))
    return default


def shifted_scene(data: dict[str, Any], cameras: Sequence[str]) -> dict[str, Any]:
    """The config with its visual randomization replaced by the :data:`SHIFT` ranges.

    The table and light are the ones the config's own ``randomize_visual_material`` and
    ``randomize_light`` events name (``table`` and ``point`` when it has none).
    """
    out = copy.deepcopy(data)
    events = (out.setdefault("env", {}).get("events")) or {}
    events = {name: cfg for name, cfg in events.items() if not _visual_event(cfg)}
    table, light = _uid_of(data, "randomize_visual_material", "table"), _uid_of(data, "randomize_light", "point")
    events["shift_table"] = {
        "func": "randomize_visual_material",
        "mode": "reset",
        "params": {"entity_cfg": {"uid": table}, "base_color_range": SHIFT["table_color_range"]},
    }
    events["shift_light"] = {
        "func": "randomize_light",
        "mode": "reset",
        "params": {
            "entity_cfg": {"uid": light},
            "color_range": SHIFT["light_color_range"],
            "intensity_range": SHIFT["light_intensity_range"],
        },
    }
    for uid in cameras:
        events[f"shift_camera_{uid}"] = {
            "func": "randomize_camera_extrinsics",
            "mode": "reset",
            "params": {
                "entity_cfg": {"uid": uid},
                "eye_range": SHIFT["camera_eye_range"],
                "target_range": SHIFT["camera_target_range"],
            },
        }
    out["env"]["events"] = events
    out["env"]["filter_visual_rand"] = False
    return out


def build_parser() -> argparse.ArgumentParser:
    """This command's options; the rest is passed to both pipeline runs."""
    p = argparse.ArgumentParser(prog="python -m embodichain_lerobot.il_visual", description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True, help="output folder (randomized/, plain/, table.json)")
    p.add_argument("--episodes", type=int, default=100, help="test episodes per cell (default 100)")
    p.add_argument("--seed", type=int, default=3_000_000, help="reset seed of the four evaluations (default 3000000)")
    p.add_argument("--num_envs", type=int, default=2, help="envs of each evaluation (default 2)")
    return p


def _evaluate(policy: Path, config: Path, out: Path, args: argparse.Namespace) -> dict[str, Any]:
    from embodichain_lerobot.eval_cli import main as eval_main

    if not out.is_file():
        argv = ["--policy", str(policy), "--gym_config", str(config), "--episodes", str(args.episodes)]
        argv += ["--num_envs", str(args.num_envs), "--seed", str(args.seed), "--headless", "--json", str(out)]
        if eval_main([*argv, "--quiet"]) != 0:
            raise SystemExit(f"eval-policy failed for {policy} on {config}")
    return rate_summary(json.loads(out.read_text(encoding="utf-8"))["episodes"])


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run both pipelines and the four evaluations; 0 when all ran."""
    from embodichain_lerobot import il_pipeline

    args, rest = build_parser().parse_known_args(argv)
    out = args.out.resolve()
    runs = {"randomized": [], "plain": ["--no_visual_randomization"]}
    for name, extra in runs.items():
        il_pipeline.main(["--policy", "camera", "--out", str(out / name), *rest, *extra])
    base = json.loads((out / "randomized" / "config.json").read_text(encoding="utf-8"))
    cameras = [s["uid"] for s in base.get("sensor") or []]
    scenes = {"nominal": nominal_scene(base), "shifted": shifted_scene(base, cameras)}
    for scene, data in scenes.items():
        (out / f"{scene}.json").write_text(json.dumps(data, indent=1), encoding="utf-8")
    table: dict[str, Any] = {"episodes": args.episodes, "seed": args.seed, "shift": SHIFT, "cells": {}}
    for name in runs:
        results = json.loads((out / name / "results.json").read_text(encoding="utf-8"))
        step, policy = results["chosen_step"], Path(results["chosen_policy"])
        for scene in scenes:
            cell = _evaluate(policy, out / f"{scene}.json", out / "eval" / f"{name}_{scene}.json", args)
            table["cells"][f"{name}/{scene}"] = {"step": step, **cell}
    (out / "table.json").write_text(json.dumps(table, indent=2) + "\n", encoding="utf-8")
    title = f"{base['id']} camera policy: with and without visual randomization"
    plot_rate_table(
        {k: {x: v for x, v in c.items() if x != "per_episode"} for k, c in table["cells"].items()},
        out / "table.png",
        title,
    )
    print(f"{'trained':<12}{'nominal scene':<30}shifted scene")
    for name in runs:
        cells = [format_rate(table["cells"][f"{name}/{s}"]) for s in scenes]
        print(f"{name:<12}{cells[0]:<30}{cells[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
