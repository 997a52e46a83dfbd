"""Where the data-generation job waits for the GPU: ``--case syncs`` of ``gpu_main_job.py``.

The main job's env (PickFork-v1 as ``main_job.json`` configures it, without the recorder,
whose copy of the frames off the device is its job) on backend ``warp``: torch's sync check
(``torch.cuda.set_sync_debug_mode("warn")``, through :class:`gpu_step_profile.SyncCounter`)
and Warp's own waits are counted over the scripted plan of one episode and over ``--steps``
steps in its middle, each step with the data-generation loop's one read of the per-env done
and success flags. On a CUDA GPU this is the check the device audit
(``tests/test_device_audit_main_job.py``: 2 waits per step, 75 per plan with 2 envs on Warp's
CPU device) cannot make: syncs inside libraries, and the pageable host copies torch reports.
On Warp's CPU device only Warp's waits are counted (torch's check needs CUDA).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from typing import Any

from gpu_step_profile import SyncCounter

TOP_SITES = 12


def main_job_env(num_envs: int, args: argparse.Namespace, workdir: str) -> Any:
    """The main job's env on backend warp (``args.device``), without its recorder."""
    from gpu_main_job import job_config

    from embodichain_core.cli.run_env import build_parser, prepare
    from embodichain_core.cli.run_loops import make_env

    save_path = tempfile.mkdtemp(prefix=f"syncs_{num_envs}_", dir=workdir)
    path, _ = job_config(save_path, num_envs, num_envs, args)
    with open(path, encoding="utf-8") as f:
        cfg = json.load(f)
    cfg["env"].pop("dataset", None)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(cfg, f)
    argv = ["--gym_config", path, "--headless", "--quiet", "--max_episodes", str(num_envs), "--seed", "0"]
    return make_env(prepare(build_parser().parse_args(argv)))


def measure_syncs(num_envs: int, args: argparse.Namespace, workdir: str) -> dict[str, Any]:
    """One row of ``--case syncs``: host waits per plan and per step, with their sites."""
    from embodichain_core.cli.run_loops import _done_success

    cuda = args.device.startswith("cuda")
    env = main_job_env(num_envs, args, workdir)
    base = env.unwrapped
    try:
        env.reset(options={"save_data": False})
        with SyncCounter(cuda) as plan:
            actions = base.create_demo_action_list()
        env.step(actions[0])  # first-step work (lazy caches) stays out of the count
        steps = max(1, min(args.steps, len(actions) - 1))
        with SyncCounter(cuda) as syncs:
            for action in actions[1 : steps + 1]:
                _, _, terminated, truncated, info = env.step(action)
                _done_success(terminated, truncated, info, num_envs)
    finally:
        env.close()
    per_step = syncs.summary(steps)
    return {
        "case": "syncs",
        "num_envs": num_envs,
        "steps": steps,
        "torch_sync_check": cuda,
        "per_step": per_step["per_step"],
        "per_step_by_kind": per_step["per_step_by_kind"],
        "sites": per_step["sites"][:TOP_SITES],
        "plan_syncs": plan.summary(1)["per_step"],
        "plan_sites": plan.summary(1)["sites"][:TOP_SITES],
    }
