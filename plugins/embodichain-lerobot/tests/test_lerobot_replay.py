"""Datasets describe their env (``meta/embodichain_env.json``) and replay exactly.

One recording of the main job (PickFork-v1, 2 envs, the shipped recorder with
``environment_state``) with a 64x48 stereo camera: 4 episodes, so each env records a
second episode after its autoreset. ``embodichain dataset replay`` re-simulates every
episode bit-exactly; an altered action fails naming episode, frame and feature.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import embodichain_tasks
import numpy as np
import pytest

from embodichain_lerobot import cli
from embodichain_lerobot.env_meta import ENV_META, read_env_meta, version_mismatches
from embodichain_lerobot.env_state import ENV_STATE
from embodichain_lerobot.reading import load_dataset, read_sidecar

MAIN_JOB = Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json"


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The main job with a 64x48 camera and 4 episodes of 2 envs, recorded by run-env."""
    from embodichain_core.cli import run_env

    tmp = tmp_path_factory.mktemp("replay")
    data = json.loads(MAIN_JOB.read_text(encoding="utf-8"))
    cam = data["sensor"][0]
    cam.update(width=64, height=48, intrinsics=[30.0, 30.0, 32.0, 24.0], intrinsics_right=[30.0, 30.0, 32.0, 24.0])
    data["max_episodes"] = 4
    data["env"]["seed"] = 0  # the shipped config draws a seed per run; here every scripted demo succeeds
    data["env"]["dataset"]["lerobot"]["params"]["save_path"] = str(tmp / "datasets")
    config = tmp / "main_job_small.json"
    config.write_text(json.dumps(data), encoding="utf-8")
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    (root,) = (tmp / "datasets").iterdir()
    return root


def _replay(capsys: Any, *argv: str) -> tuple[int, str, str]:
    code = cli.main(["replay", *argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_the_dataset_describes_its_env_and_lerobot_still_loads_it(dataset: Path) -> None:
    meta = read_env_meta(dataset)
    assert meta["task_id"] == "PickFork-v1"
    assert meta["task_provider"]["plugin"] == "embodichain-tasks"
    assert meta["backend"] == "mujoco_batch"
    assert meta["env_cfg"]["num_envs"] == 2
    assert meta["env_cfg"]["sensor"][0]["width"] == 64  # the resolved config, not the shipped file
    assert {"embodichain-core", "mujoco", "lerobot", "torch", "embodichain-tasks"} <= set(meta["versions"])
    assert version_mismatches(meta) == []
    ds = load_dataset(dataset)
    assert ds.num_episodes == 4
    assert tuple(ds[0][ENV_STATE].shape) == (16,)


def test_environment_state_replaces_the_task_observation_with_named_elements(dataset: Path) -> None:
    features = json.loads((dataset / "meta" / "info.json").read_text())["features"]
    assert "fork_pose" not in features
    state = features[ENV_STATE]
    assert state["dtype"] == "float32"
    assert state["shape"] == [16]
    assert state["names"][:2] == ["fork_pose[0,0]", "fork_pose[0,1]"]
    assert state["names"][3] == "fork_pose[0,3]"  # the fork's x in the env frame


def test_every_episode_replays_exactly_including_those_after_an_autoreset(
    dataset: Path, tmp_path: Path, capsys: Any
) -> None:
    env_ids = [r["env_id"] for r in read_sidecar(dataset)]
    assert sorted(env_ids) == [0, 0, 1, 1]  # each env recorded an episode after its autoreset
    report = tmp_path / "replay.json"
    code, out, _ = _replay(capsys, str(dataset), "--all", "--json", str(report))
    assert code == 0, out
    assert "replayed 4 episode(s): 4 within tolerance, 0 not" in out
    data = json.loads(report.read_text())
    assert data["ok"] is True
    assert data["atol"] == 0.0
    for episode in data["episodes"]:
        assert set(episode["max_error"]) >= {"observation.state", ENV_STATE, "observation.qvel", "next.success"}
        assert max(episode["max_error"].values()) == 0.0
        assert min(episode["min_psnr"].values()) > 25.0


def _alter_action(src: Path, dest: Path, episode: int, frame: int) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    shutil.copytree(src, dest)
    for path in sorted((dest / "data").rglob("*.parquet")):
        table = pq.read_table(path)
        rows = table.to_pydict()
        hits = [
            i for i, (e, f) in enumerate(zip(rows["episode_index"], rows["frame_index"])) if (e, f) == (episode, frame)
        ]
        if hits:
            action = np.asarray(rows["action"][hits[0]], dtype=np.float32)
            action[0] += 0.05  # the first arm joint's target, 0.05 rad off
            rows["action"][hits[0]] = action.tolist()
            pq.write_table(pa.Table.from_pydict(rows, schema=table.schema), path)
            return
    raise AssertionError(f"no frame {frame} of episode {episode}")


def test_an_altered_action_fails_naming_episode_frame_and_feature(dataset: Path, tmp_path: Path, capsys: Any) -> None:
    altered = tmp_path / "altered"
    _alter_action(dataset, altered, episode=1, frame=30)
    code, out, err = _replay(capsys, str(altered), "--episode", "1", "--image_frames", "0")
    assert code == 1, out + err
    assert "FAILED: episode 1, frame 31, feature observation.state" in out
    assert "0 within tolerance, 1 not" in out


def test_another_version_replays_with_a_warning_naming_the_versions(dataset: Path, tmp_path: Path, capsys: Any) -> None:
    other = tmp_path / "other_version"
    shutil.copytree(dataset, other)
    meta = json.loads((other / ENV_META).read_text())
    meta["versions"]["mujoco"] = "3.3.0"
    (other / ENV_META).write_text(json.dumps(meta))
    code, out, err = _replay(capsys, str(other), "--episode", "0", "--image_frames", "0")
    assert code == 0, out
    assert "recorded with other versions (mujoco: recorded 3.3.0, running" in err


def test_a_dataset_without_the_description_is_refused_clearly(dataset: Path, tmp_path: Path, capsys: Any) -> None:
    bare = tmp_path / "bare"
    shutil.copytree(dataset, bare)
    (bare / ENV_META).unlink()
    code, _, err = _replay(capsys, str(bare))
    assert code == 2
    assert "embodichain_env.json does not exist" in err


def test_eval_policy_builds_the_recorded_environment_state_from_the_env(dataset: Path) -> None:
    """The policy's ``observation.environment_state`` is what the recorder stored (one mapping)."""
    from types import SimpleNamespace

    import torch
    from lerobot.configs.types import FeatureType, PolicyFeature

    from embodichain_core.cli import run_env
    from embodichain_lerobot import eval_cli
    from embodichain_lerobot.episode_reader import EpisodeFiles
    from embodichain_lerobot.policy_inputs import ObservationMapper

    config = dataset.parents[1] / "main_job_small.json"
    args = eval_cli.build_parser().parse_args(["--policy", "-", "--gym_config", str(config), "--episodes", "2"])
    env = run_env.make_env(eval_cli._plan(args))
    seeds = [r["episode_seed"] for r in read_sidecar(dataset)[:2]]
    try:
        obs, _ = env.reset(options={"episode_seeds": seeds})
        policy = SimpleNamespace(input_features={ENV_STATE: PolicyFeature(FeatureType.ENV, (16,))})
        mapped = ObservationMapper(obs, env.unwrapped, policy)(obs)[ENV_STATE]
    finally:
        env.close()
    for row in range(2):
        recorded = EpisodeFiles(dataset, row).series(ENV_STATE)[0]
        torch.testing.assert_close(mapped[row], torch.as_tensor(recorded, dtype=torch.float32), rtol=0, atol=0)
