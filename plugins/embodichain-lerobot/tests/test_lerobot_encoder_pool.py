"""Video encoding spread over encoder processes (``params.encoder_processes``).

The param's checks and its ``"auto"`` count; an encoder process's work in-process (a
restarted episode leaves no video, a finished one is published under its ticket); the
dataset writer's wait for a video whose encoder is gone; and, slow: the main job (PickFork-v1,
2 envs, 64x48 stereo camera, 4 episodes) recorded with 2 encoder processes equals the one
recorded with the writer process encoding (same episodes and data, frames within codec
tolerance) and replays; a ``SIGKILL`` of the recording process keeps every episode it had
handed to the dataset writer.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from embodichain_core.config.errors import ConfigError
from embodichain_lerobot.config import MAX_ENCODER_PROCESSES, encoder_process_count
from embodichain_lerobot.encoder_child import EncoderChild
from embodichain_lerobot.encoder_files import ENCODING, result_path, wait_result
from embodichain_lerobot.recorder import LeRobotRecorder
from lerobot_helpers import arm_cfg, recorder_cfg


@pytest.mark.parametrize("value", [0, -1, 2.5, "two", True, MAX_ENCODER_PROCESSES + 1])
def test_a_bad_encoder_process_count_names_its_key(value: Any) -> None:
    message = rf"env\.dataset\.rec\.params\.encoder_processes: must be 'auto' or an int from 1 to 64, got {value!r}"
    with pytest.raises(ConfigError, match=message):
        LeRobotRecorder.preflight({"save_path": "/tmp", "encoder_processes": value}, "env.dataset.rec")


def test_a_bad_encoder_process_count_is_one_error_at_build(make_env: Any, tmp_path: Path) -> None:
    cfg = arm_cfg(1, dataset=recorder_cfg(tmp_path, use_videos=True, encoder_processes=0))
    with pytest.raises(ConfigError) as err:
        make_env(cfg)
    assert str(err.value) == "env.dataset.rec.params.encoder_processes: must be 'auto' or an int from 1 to 64, got 0"


def test_encoder_processes_without_streamed_videos_to_a_writer_process_is_refused(
    make_env: Any, tmp_path: Path
) -> None:
    cfg = arm_cfg(2, dataset=recorder_cfg(tmp_path, use_videos=False, writer_process=True, encoder_processes=2))
    with pytest.raises(ConfigError, match=r"params\.encoder_processes: 2 encoder processes encode streamed videos"):
        make_env(cfg)


@pytest.mark.parametrize(
    "setting, num_envs, cpus, count",
    [
        ("auto", 4, 2, 1),
        ("auto", 4, 5, 1),
        ("auto", 64, 8, 3),
        ("auto", 64, 16, 7),
        ("auto", 2, 16, 2),
        (3, 8, 2, 3),
        (8, 2, 2, 2),
    ],
)
def test_the_encoder_process_count(setting: Any, num_envs: int, cpus: int, count: int) -> None:
    assert encoder_process_count(setting, num_envs, cpus) == count


def _frames(value: int, n: int = 2) -> np.ndarray:
    """``n`` RGBA frames (the recorder sends colour with its alpha), 16x16."""
    return np.full((n, 16, 16, 4), value, np.uint8)


def test_an_encoder_process_cancels_a_restart_and_publishes_a_finished_episode(tmp_path: Path) -> None:
    folder = tmp_path / "dataset" / ENCODING
    folder.parent.mkdir()
    child = EncoderChild()
    child.handle("open", (str(folder), 10, "h264", None, ["cam"], []))
    for t in range(3):  # envs 0 and 1 run an episode each
        child.handle("frames", ({"cam": _frames(40 * t)}, [0, 1]))
    child.handle("restart", [0])  # env 0's episode ends without a commit
    assert len([p for p in folder.iterdir() if p.is_dir()]) == 1  # env 0's temporary video is gone
    child.handle("finish", (1, "env1_0"))
    videos = wait_result(folder, "env1_0", pid=0)
    (mp4, stats) = videos["cam"]
    from embodichain_lerobot.encoding import video_frame_count

    assert video_frame_count(mp4) == 3
    assert stats is not None
    assert set(stats) >= {"min", "max", "mean", "std"}
    child.handle("finish", (0, "env0_1"))  # nothing left of env 0's episode: an error, named
    with pytest.raises(RuntimeError, match="no video frame of env 0's episode reached its encoder process"):
        wait_result(folder, "env0_1", pid=0)
    child.handle("frames", ({"cam": _frames(7, 1)}, [0]))
    child.finalize()  # the live episode of env 0 is cancelled
    assert [p for p in folder.iterdir() if p.is_dir()] == [mp4.parent]  # only the finished video is left
    assert not result_path(folder, "env1_0").exists()


def test_an_encoder_process_never_recreates_a_dataset_folder_the_writer_removed(tmp_path: Path) -> None:
    folder = tmp_path / "dataset" / ENCODING  # the writer could not create the dataset and removed its folder
    child = EncoderChild()
    child.handle("open", (str(folder), 10, "h264", None, ["cam"], []))
    child.handle("frames", ({"cam": _frames(9)}, [0, 1]))
    child.handle("finish", (0, "env0_0"))
    child.finalize()
    assert not (tmp_path / "dataset").exists()


def test_the_writer_does_not_wait_for_a_video_whose_encoder_is_gone(tmp_path: Path) -> None:
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    with pytest.raises(RuntimeError, match=rf"video encoder process \(pid {gone.pid}\) exited before it finished"):
        wait_result(tmp_path, "env3_7", gone.pid)


# -- the main job, recorded twice --------------------------------------------------------------------


def _record_main_job(tmp: Path, encoder_processes: int) -> Path:
    import embodichain_tasks

    from embodichain_core.cli import run_env

    data = json.loads((Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json").read_text())
    cam = data["sensor"][0]
    cam.update(width=64, height=48, intrinsics=[30.0, 30.0, 32.0, 24.0], intrinsics_right=[30.0, 30.0, 32.0, 24.0])
    data["max_episodes"] = 4
    data["env"]["seed"] = 0  # every scripted demo succeeds
    params = data["env"]["dataset"]["lerobot"]["params"]
    params.update(save_path=str(tmp / "datasets"), encoder_processes=encoder_processes)
    config = tmp / "main_job_small.json"
    config.write_text(json.dumps(data), encoding="utf-8")
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    (root,) = (tmp / "datasets").iterdir()
    return root


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The main job recorded with the writer process encoding (1) and with 2 encoder processes."""
    return {n: _record_main_job(tmp_path_factory.mktemp(f"encoders{n}"), n) for n in (1, 2)}


@pytest.mark.slow  # two main-job recordings (~30-60 s each on 2 loaded cores)
def test_two_encoder_processes_record_the_same_dataset(recorded: dict[int, Path]) -> None:
    from embodichain_lerobot.reading import load_dataset, read_sidecar

    one, two = (load_dataset(recorded[n]) for n in (1, 2))
    assert two.num_episodes == one.num_episodes == 4
    assert list(two.meta.episodes["length"]) == list(one.meta.episodes["length"])
    assert [r["env_id"] for r in read_sidecar(recorded[2])] == [r["env_id"] for r in read_sidecar(recorded[1])]
    info = [json.loads((recorded[n] / "meta" / "info.json").read_text()) for n in (1, 2)]
    assert info[1]["features"] == info[0]["features"]  # video codec, pixel format, shapes alike
    video_keys = set(one.meta.video_keys)
    assert video_keys == {"observation.images.eye_in_head", "observation.images.eye_in_head_right"}
    plain = [c for c in one.hf_dataset.column_names if c not in video_keys]
    assert one.hf_dataset.select_columns(plain).to_pandas().equals(two.hf_dataset.select_columns(plain).to_pandas())
    for i in range(0, len(one), 7):  # every 7th frame, decoded from each video
        a, b = one[i], two[i]
        for key in video_keys:
            diff = np.abs(a[key].numpy() - b[key].numpy())
            assert diff.mean() < 2 / 255, (i, key, diff.mean())
            assert diff.max() < 0.25, (i, key, diff.max())
    assert not (recorded[2] / ENCODING).exists()


@pytest.mark.slow
def test_the_dataset_of_two_encoder_processes_replays(recorded: dict[int, Path], capsys: Any) -> None:
    from embodichain_lerobot import cli

    code = cli.main(["replay", str(recorded[2]), "--all"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "replayed 4 episode(s): 4 within tolerance, 0 not" in out


@pytest.mark.slow  # a recording process with a camera, its writer and 2 encoder processes (~30-60 s)
def test_a_killed_recording_process_with_encoder_processes_loses_no_handed_episode(tmp_path: Path) -> None:
    pytest.importorskip("embodichain_sensors")
    from test_lerobot_crash import check_loads, the_dataset
    from test_lerobot_kill import STAGING, Gated, _wait_finalized

    params = {"use_videos": True, "vcodec": "h264", "encoder_processes": 2}
    rec = Gated(tmp_path, allowed=1, camera=True, params=params)
    rec.wait_for(committed=1, sent=3)  # one saved, two more queued in the writer process
    rec.proc.kill()
    rec.proc.wait()
    rec.open(10_000)  # the orphaned writer may now write what it holds, with the encoders' videos
    path = the_dataset(rec.save_path)
    _wait_finalized(path)
    episodes = check_loads(path, at_least=rec.seen["SENT"])  # every frame read, videos decoded
    assert episodes >= 3
    assert not (path / STAGING).exists()
    assert not (path / ENCODING).exists()
    assert "failed" not in rec.errors(), rec.errors()
