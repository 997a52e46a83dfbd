"""Per-episode seeds: each saved episode's line in ``meta/embodichain_episodes.jsonl``
holds ``episode_seed``, the env's episode seed when the episode was committed, and
``embodichain dataset info`` shows it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from lerobot_helpers import ScriptedEnv, arm_cfg, datasets_under, load, recorder_cfg, reset, run_script

from embodichain_lerobot.cli import main as dataset_cli
from embodichain_lerobot.reading import read_sidecar

BIG = 2**64 - 5  # uint64 seeds above 2**63 survive the JSON round trip


def record(make_env: Callable, tmp_path: Path, script: list[list[str]]) -> tuple[Path, list[np.ndarray]]:
    """Record ``script`` with 2 envs whose first episodes get the seeds 111 and ``BIG``;
    return the dataset and ``env.episode_seeds`` before each step (``[]`` without it)."""
    env = make_env(arm_cfg(2, dataset=recorder_cfg(tmp_path)))
    reset(env)
    has_seeds = getattr(env, "episode_seeds", None) is not None
    if has_seeds:
        env.last_obs, _ = env.reset(options={"episode_seeds": [111, BIG]})
    seen = []
    for row in script:
        if has_seeds:
            seen.append(env.episode_seeds.copy())
        run_script(env, [row])
    env.close()
    (path,) = datasets_under(tmp_path)
    return path, seen


def test_every_episode_records_its_seed(make_env: Callable, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    path, seen = record(make_env, tmp_path, [["s", "."], [".", "s"], ["s", "."]])
    assert seen, "the env exposes episode_seeds"
    records = read_sidecar(path)
    assert [(r["env_id"], r["episode_seed"]) for r in records] == [(0, 111), (1, BIG), (0, int(seen[2][0]))]
    assert int(seen[2][0]) != 111  # env 0's 2nd episode drew a new seed after its reset
    assert load(path).num_episodes == 3
    assert dataset_cli(["info", str(path), "--episodes"]) == 0
    out = capsys.readouterr().out
    assert "seeds     3/3 episodes have an episode_seed (111, 18446744073709551611" in out
    rows = out.split("episode_seed\n")[-1].splitlines()
    assert rows[1].split() == ["1", "2", "yes", "1", str(BIG)]  # env 1 ran 2 steps
    assert dataset_cli(["info", str(path), "--json", "--episodes"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["episode_seeds"] == [111, BIG, int(seen[2][0])]
    assert [r["episode_seed"] for r in summary["episode_records"]] == summary["episode_seeds"]


def test_an_env_without_episode_seeds_records_none(
    make_env: Callable, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.setattr(ScriptedEnv, "episode_seeds", None, raising=False)  # an env from before the seeds
    path, seen = record(make_env, tmp_path, [["s", "s"]])
    assert seen == []
    assert [r.get("episode_seed", "absent") for r in read_sidecar(path)] == ["absent"] * 2
    assert dataset_cli(["info", str(path), "--episodes"]) == 0
    out = capsys.readouterr().out
    assert "seeds " not in out
    assert out.splitlines()[-1].split() == ["1", "1", "yes", "1", "-"]
