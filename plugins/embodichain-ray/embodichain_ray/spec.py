"""What a generation run is: its parameters, the episode seeds and where the shards go.

Episode ``k`` of a run with seed ``S`` is a function of ``(S, k)`` alone, whatever the
number of workers ``W`` and envs per worker ``K``:

* attempt 0 of episode ``k`` uses the episode seed ``derive_seed(S, k)``;
* a failed scripted demo is retried with attempt ``a >= 1`` and seed ``derive_seed(S, k, a)``,
  up to the config's ``demo_max_attempts`` attempts in all.

The recorder stores each episode's seed, so :func:`seed_table` maps a recorded seed back
to its ``(k, a)`` when the shards are merged (64-bit seeds: collisions are negligible and
checked for).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from embodichain_core.envs.episode_rng import derive_seed

#: Folder of worker ``w``'s shards under the shards folder (each incarnation adds a ``_NNN`` folder inside).
WORKER_DIR = "worker-{:03d}"
#: Created by the driver to stop the workers (Ctrl-C, SIGTERM); removed when a run starts.
STOP_FILE = ".stop"


def episode_seed(seed: int, episode: int, attempt: int = 0) -> int:
    """The episode seed of attempt ``attempt`` of episode ``episode`` of a run seeded ``seed``."""
    if attempt == 0:
        return int(derive_seed(seed, episode))
    return int(derive_seed(seed, episode, attempt))


def padding_seed(seed: int, slot: int) -> int:
    """The seed of an idle env slot (its episodes are never merged): ``derive_seed(S, 2**63 + slot)``."""
    return int(derive_seed(seed, 2**63 + slot))


def seed_table(seed: int, episodes: int, attempts: int) -> dict[int, tuple[int, int]]:
    """Map every episode seed a run can use to its ``(episode, attempt)``.

    Raises:
        ValueError: two (episode, attempt) pairs share a seed (never seen with 64-bit seeds).
    """
    table: dict[int, tuple[int, int]] = {}
    for k in range(episodes):
        for a in range(attempts):
            s = episode_seed(seed, k, a)
            if s in table:
                raise ValueError(f"episode seeds collide: {table[s]} and {(k, a)} both map to {s}")
            table[s] = (k, a)
    return table


@dataclass
class GenerateSpec:
    """The parameters of ``embodichain generate``.

    Attributes:
        task: a task id or ``None`` (then ``gym_config`` names the config).
        gym_config: a JSON/YAML gym config file, or ``None``.
        episodes: episodes to save (``N``).
        workers: Ray actors (``W``).
        num_envs: parallel envs per worker (``K``).
        seed: the run's seed (``S``).
        output: the merged dataset folder (must not exist).
        shards: the folder of the workers' shards.
        ray_address: an existing Ray cluster to join (``None``: an embedded local one).
        max_restarts: how often Ray restarts a dead worker.
        keep_shards: keep the shards after a successful merge.
        merge_only: run no worker, only merge what ``shards`` holds.
        show_bar: draw the progress bar.
        close_timeout: seconds a stop (Ctrl-C, ``SIGTERM``) gives the workers to finish their
            round, wait for their writers and close their shards before they are killed.
        dashboard: start the embedded Ray's dashboard (off unless asked).
        progress_every: without the bar, seconds between plain progress lines (0: none).
        transport: how shards reach the driver: ``shared`` (``shards`` is a folder every
            worker writes), ``ray`` (the object store) or a storage URI (see
            :mod:`embodichain_ray.transport`).
        scratch: with ``ray`` or a URI, the folder on each worker's node it records into
            (``None``: the node's ``EMBODICHAIN_GENERATE_SCRATCH``, else its temp folder).
    """

    task: str | None
    gym_config: str | None
    episodes: int
    workers: int
    num_envs: int
    seed: int
    output: Path
    shards: Path
    ray_address: str | None = None
    max_restarts: int = 3
    keep_shards: bool = False
    merge_only: bool = False
    show_bar: bool = False
    close_timeout: float = 60.0
    dashboard: bool = False
    progress_every: float = 0.0
    transport: str = "shared"
    scratch: str | None = None

    def worker_dir(self, worker: int) -> Path:
        """Where worker ``worker`` records (its recorder's ``save_path``)."""
        return self.shards / WORKER_DIR.format(worker)

    @property
    def stop_file(self) -> Path:
        """The file whose existence asks every worker to stop after its current step."""
        return self.shards / STOP_FILE


def run_env_argv(spec: GenerateSpec) -> list[str]:
    """The ``run-env`` arguments that load the same config (the workers' env and the driver's check)."""
    argv = [spec.task] if spec.task else []
    if spec.gym_config:
        argv += ["--gym_config", spec.gym_config]
    return argv + ["--num_envs", str(spec.num_envs), "--seed", str(spec.seed), "--headless", "--quiet"]


def parse_run_env_args(argv: list[str]) -> argparse.Namespace:
    """Parse ``argv`` with ``run-env``'s own parser (its defaults for every other option)."""
    from embodichain_core.cli.run_env import build_parser

    return build_parser().parse_args(argv)
