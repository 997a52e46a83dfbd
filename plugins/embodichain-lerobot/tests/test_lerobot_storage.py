"""Output folders and full disks: ``run-env`` refuses a read-only or full dataset folder
before the env is built; a disk that fills up mid-run ends the run with a clear error,
the saved episodes finalized and loadable, and the summary printed."""

from __future__ import annotations

import errno
import json
import os
import stat
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterator

import pytest

from lerobot_helpers import arm_cfg, datasets_under, load, recorder_cfg, reset, run_script
from test_lerobot_run_env import write_config

from embodichain_core.cli import run_env
from embodichain_lerobot import storage
from embodichain_lerobot.folders import clean_incomplete, folder_status
from embodichain_lerobot.reading import check_dataset_dir
from embodichain_lerobot.storage import DiskFullError

KEY = "env.dataset.lerobot.params.save_path"


@pytest.fixture
def read_only_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A folder nobody can write into. Root ignores mode bits, so for root a read-only
    filesystem is simulated: creating a file in it fails with ``EROFS``."""
    path = tmp_path / "ro"
    path.mkdir()
    path.chmod(stat.S_IRUSR | stat.S_IXUSR)
    if os.geteuid() == 0:
        original = tempfile.mkstemp

        def mkstemp(*args: Any, **kwargs: Any) -> Any:
            if Path(kwargs.get("dir") or "").resolve() == path.resolve():
                raise OSError(errno.EROFS, "Read-only file system")
            return original(*args, **kwargs)

        monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    yield path
    path.chmod(stat.S_IRWXU)


def run(config: Path, capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = run_env.main(["--gym_config", str(config), "--quiet"])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_a_read_only_dataset_folder_fails_before_the_build(
    tmp_path: Path, task_id: str, read_only_dir: Path, capsys: pytest.CaptureFixture
) -> None:
    save_path = read_only_dir / "datasets"
    code, out, err = run(write_config(tmp_path / "c.json", task_id, save_path, "LeRobotRecorder"), capsys)
    assert code == 2
    assert "Traceback" not in err
    assert "run-env summary" not in out
    assert f"{KEY}: dataset folder {save_path} is not writable (it would be created in {read_only_dir})" in err
    assert "--filter_dataset_saving" in err
    assert list(read_only_dir.iterdir()) == []


def test_too_little_free_space_fails_before_the_build(
    tmp_path: Path, task_id: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.setattr(storage, "free_mb", lambda path: 40.0)
    code, _, err = run(write_config(tmp_path / "c.json", task_id, tmp_path / "data", "LeRobotRecorder"), capsys)
    assert code == 2
    assert f"{KEY}: only 40 MB free on the filesystem of the dataset folder {tmp_path / 'data'}" in err
    assert "at least 256 MB (its params.min_free_mb)" in err
    assert not (tmp_path / "data").exists()


def test_a_save_path_below_a_file_is_refused(tmp_path: Path) -> None:
    from embodichain_core.config.errors import ConfigError
    from embodichain_lerobot.recorder import LeRobotRecorder

    (tmp_path / "file").write_text("")
    with pytest.raises(ConfigError, match=r"env.dataset.x.params.save_path: .* is not a directory"):
        LeRobotRecorder.preflight({"save_path": str(tmp_path / "file" / "data")}, "env.dataset.x")


FAIL_THIRD_SAVE = """
import errno
from lerobot.datasets.lerobot_dataset import LeRobotDataset

_original, _calls = LeRobotDataset.save_episode, []


def save_episode(self, *args, **kwargs):
    _calls.append(1)
    _original(self, *args, **kwargs)
    if len(_calls) == 3:  # the 3rd save writes its files, then the disk is full
        raise OSError(errno.ENOSPC, "No space left on device")


LeRobotDataset.save_episode = save_episode
"""


def fail_third_save(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, writer_process: bool) -> None:
    """lerobot's 3rd ``save_episode`` writes its files, then the disk is full: patched here,
    or in the writer process (a ``sitecustomize`` module on its ``PYTHONPATH``)."""
    if writer_process:
        hook = tmp_path / "hook"
        hook.mkdir()
        (hook / "sitecustomize.py").write_text(FAIL_THIRD_SAVE + "\n")
        monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(hook), os.environ.get("PYTHONPATH")])))
        return
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    original = LeRobotDataset.save_episode
    exec(FAIL_THIRD_SAVE, {})  # patches the class
    patched, LeRobotDataset.save_episode = LeRobotDataset.save_episode, original
    monkeypatch.setattr(LeRobotDataset, "save_episode", patched)  # undone after the test


@pytest.mark.parametrize(
    "func, writer_process",
    [
        ("LeRobotRecorder", False),
        ("LeRobotRecorder", True),
        ("AsyncLeRobotRecorder", False),
        ("AsyncLeRobotRecorder", True),
    ],
)
def test_a_disk_full_mid_run_keeps_the_saved_episodes(
    tmp_path: Path,
    task_id: str,
    func: str,
    writer_process: bool,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture,
) -> None:
    fail_third_save(monkeypatch, tmp_path, writer_process)
    config = write_config(tmp_path / "c.json", task_id, tmp_path / "data", func)
    data = json.loads(config.read_text())
    data["env"]["dataset"]["lerobot"]["params"]["writer_process"] = writer_process
    config.write_text(json.dumps(data))
    code, out, err = run(config, capsys)
    path = tmp_path / "data" / "arm7_empty_reach_000"
    assert code == 1
    last = err.strip().splitlines()[-1]
    if func == "LeRobotRecorder":  # raised by the commit inside env.reset
        assert "while running episodes: DiskFullError in functor env.dataset.lerobot: [Errno 28]" in last
    else:  # the worker's error surfaces when the recorder is finalized
        assert "while closing the env: DiskFullError in functor env.dataset.lerobot:" in last
    assert f"no space left on device while saving episode 2 to {path}" in last
    assert "the 2 episode(s) saved before it are intact" in last
    assert "saved        2 episode(s)" in out
    assert f"data         {path}" in out
    assert "stopped      early" in out
    ds = load(path)
    assert ds.num_episodes == 2
    assert len(ds) == 8
    assert not (path / ".embodichain_staging").exists()
    assert not (path / ".embodichain_recording").exists()


def full_while_adding_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    def add_frame(self: Any, frame: dict) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(LeRobotDataset, "add_frame", add_frame)


@pytest.mark.parametrize(
    "fault, message",
    [
        ("low_space", "not enough disk space to save episode 2 .* 100 MB free"),
        ("add_frame", "no space left on device while saving episode 2 .* the 2 episode.s. saved before it are intact"),
    ],
)
def test_a_full_disk_stops_between_episodes(
    make_env: Callable, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fault: str, message: str
) -> None:
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    run_script(env, [["s"], ["s"]])
    if fault == "low_space":
        monkeypatch.setattr(storage, "free_mb", lambda path: 100.0)
    else:
        full_while_adding_frames(monkeypatch)
    with pytest.raises(DiskFullError, match=message) as info:
        run_script(env, [["s"]])
    assert "raised in functor env.dataset.rec (LeRobotRecorder)" in info.value.__notes__
    env.close()
    (path,) = datasets_under(tmp_path)
    assert rec.saved_episodes == 2
    assert load(path).num_episodes == 2


def test_a_failed_publish_leaves_no_metadata_line_behind(
    make_env: Callable, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from embodichain_lerobot import writer
    from embodichain_lerobot.reading import dataset_summary, read_sidecar

    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    reset(env)
    run_script(env, [["s"], ["s"]])
    original = writer.atomic_copy

    def copy(src: Path, dest: Path) -> None:
        if dest.name == "info.json":  # the commit point of the 3rd episode
            raise OSError(errno.ENOSPC, "No space left on device")
        original(src, dest)

    monkeypatch.setattr(writer, "atomic_copy", copy)
    with pytest.raises(DiskFullError):
        run_script(env, [["s"]])
    env.close()
    (path,) = datasets_under(tmp_path)
    assert len((path / writer.SIDECAR).read_text().splitlines()) == 3  # written before the commit point
    assert [r["lerobot_episode_index"] for r in read_sidecar(path)] == [0, 1]
    assert dataset_summary(path)["successes"] == 2
    assert load(path).num_episodes == 2


def test_a_live_recording_without_episodes_is_left_alone(make_env: Callable, tmp_path: Path) -> None:
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    run_script(env, [["."]])
    writer = rec._ensure_writer()  # the folder exists; no episode is saved yet
    status = folder_status(writer.root)
    assert status.owner is not None
    assert status.owner["pid"] == os.getpid()
    assert not status.removable
    assert clean_incomplete(tmp_path, writer.root.name.rsplit("_", 1)[0]) == []
    with pytest.raises(FileNotFoundError, match=f"{writer.root} is being recorded by process {os.getpid()}"):
        check_dataset_dir(writer.root)
    env.close()
    assert datasets_under(tmp_path) == []  # nothing saved: the folder is removed


def test_lerobots_encoder_thread_disk_full_lines_are_dropped_and_other_errors_kept(
    caplog: pytest.LogCaptureFixture,
) -> None:
    import logging

    storage.quiet_encoder_disk_full()
    storage.quiet_encoder_disk_full()  # idempotent
    assert logging.getLogger().filters.count(storage._ENCODER_FILTER) == 1
    with caplog.at_level(logging.ERROR):
        logging.error("Encoder thread error: [Errno 28] No space left on device")
        logging.error("Encoder thread error: codec failed")
    assert [r.getMessage() for r in caplog.records] == ["Encoder thread error: codec failed"]


def test_finish_orphaned_removes_staging_and_a_dead_marker_and_an_unsaved_folder(tmp_path: Path) -> None:
    unsaved = tmp_path / "unsaved"
    (unsaved / "meta").mkdir(parents=True)
    (unsaved / "meta" / "embodichain_env.json").write_text("{}")
    assert storage.finish_orphaned(unsaved)
    assert not unsaved.exists()  # reserved by the dead recording, nothing saved in it
    (tmp_path / "meta").mkdir()
    (tmp_path / ".embodichain_staging").mkdir()
    (tmp_path / storage.MARKER).write_text(json.dumps({"pid": 1, "locked": True}))
    (tmp_path / "meta" / "info.json").write_text(json.dumps({"total_episodes": 0}))
    (tmp_path / "meta" / "info.json").write_text(json.dumps({"total_episodes": 2}))
    assert storage.finish_orphaned(tmp_path)
    assert not (tmp_path / ".embodichain_staging").exists()
    assert not (tmp_path / storage.MARKER).exists()
