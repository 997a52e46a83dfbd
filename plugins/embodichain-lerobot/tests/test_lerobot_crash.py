"""Crash safety: a recording process killed with SIGKILL (between episodes, while
saving, while publishing, at random moments) or interrupted with Ctrl-C leaves a
dataset that ``LeRobotDataset`` loads with every episode committed before it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Optional

import pytest

from lerobot_helpers import have_sensors, load

CHILD = Path(__file__).with_name("lerobot_crash_child.py")


class Recording:
    """The child recording process (see ``lerobot_crash_child.py``)."""

    def __init__(self, mode: str, save_path: Path, func: str = "LeRobotRecorder", camera: bool = False):
        self.proc = subprocess.Popen(
            [sys.executable, str(CHILD), mode, str(save_path), func, str(int(camera))],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        self.committed = 0

    def wait_for(self, n: int, timeout: float = 120) -> None:
        """Read ``COMMITTED`` lines until ``n`` episodes are saved."""
        deadline = time.monotonic() + timeout
        while self.committed < n:
            assert time.monotonic() < deadline, "the recording did not commit in time"
            line = self.proc.stdout.readline()
            assert line, f"the recording exited early (code {self.proc.poll()})"
            if line.startswith("COMMITTED"):
                self.committed = int(line.split()[1])

    def finish(self, sig: Optional[int] = signal.SIGKILL, timeout: float = 120) -> str:
        """Send ``sig`` (``None``: just wait), then return the rest of stdout."""
        if sig is not None:
            self.proc.send_signal(sig)
        out, _ = self.proc.communicate(timeout=timeout)
        return out


def the_dataset(save_path: Path) -> Path:
    (path,) = [p for p in save_path.iterdir() if p.is_dir()]
    return path


def check_loads(path: Path, at_least: int, at_most: Optional[int] = None) -> int:
    """Load ``path`` and read every frame; return the number of episodes."""
    ds = load(path)
    assert at_least <= ds.num_episodes <= (at_most if at_most is not None else ds.num_episodes)
    assert len(ds) == sum(int(x) for x in ds.meta.episodes["length"][: ds.num_episodes])
    for i in range(len(ds)):
        assert ds[i]["task"] == "Push the cube"
    return ds.num_episodes


def test_sigkill_between_episodes_keeps_every_committed_episode(tmp_path: Path) -> None:
    rec = Recording("hang", tmp_path)
    rec.wait_for(3)
    time.sleep(0.5)  # mid-episode: stepping a 4th episode that never ends
    rec.finish(signal.SIGKILL)
    assert rec.proc.returncode == -signal.SIGKILL
    path = the_dataset(tmp_path)
    assert check_loads(path, 3, 3) == 3
    assert (path / ".embodichain_staging").exists()  # not finalized: the run was killed


@pytest.mark.parametrize("mode", ["die_in_save", "die_in_publish"])
def test_sigkill_inside_a_save_keeps_the_episodes_before_it(tmp_path: Path, mode: str) -> None:
    rec = Recording(mode, tmp_path)
    rec.wait_for(2)
    out = rec.finish(sig=None)
    assert rec.proc.returncode == -signal.SIGKILL
    assert "COMMITTED 3" not in out
    assert check_loads(the_dataset(tmp_path), 2, 2) == 2


@pytest.mark.parametrize("func, delay", [("LeRobotRecorder", 0.05), ("AsyncLeRobotRecorder", 0.3)])
def test_sigkill_at_a_random_moment_leaves_a_loadable_dataset(tmp_path: Path, func: str, delay: float) -> None:
    rec = Recording("churn", tmp_path, func, camera=have_sensors())
    rec.wait_for(4)
    time.sleep(delay)
    rec.finish(signal.SIGKILL)
    check_loads(the_dataset(tmp_path), rec.committed)


def test_the_writer_process_finishes_the_dataset_of_a_killed_recording(tmp_path: Path) -> None:
    rec = Recording("churn", tmp_path, "AsyncLeRobotRecorder")  # params.writer_process: on by default
    rec.wait_for(3)
    rec.finish(signal.SIGKILL)
    path = the_dataset(tmp_path)
    deadline = time.monotonic() + 60
    while (path / ".embodichain_recording").exists():  # the orphaned writer finalizes on its own
        assert time.monotonic() < deadline, "the writer process did not finalize the dataset"
        time.sleep(0.1)
    assert check_loads(path, rec.committed) >= rec.committed
    assert not (path / ".embodichain_staging").exists()


def test_ctrl_c_finalizes_with_every_committed_episode(tmp_path: Path) -> None:
    rec = Recording("churn", tmp_path, "AsyncLeRobotRecorder")
    rec.wait_for(3)
    out = rec.finish(signal.SIGINT)
    assert rec.proc.returncode != 0
    assert "FINALIZED" in out
    saved = int(out.split("FINALIZED")[1].split()[0])
    path = the_dataset(tmp_path)
    assert check_loads(path, max(rec.committed, saved), saved) == saved
    assert not (path / ".embodichain_staging").exists()


def test_ctrl_c_during_a_save_lands_after_the_episode_is_saved(
    make_env, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from lerobot_helpers import arm_cfg, recorder_cfg, reset, run_script

    from embodichain_lerobot.writer import DatasetWriter

    original = DatasetWriter._continue_in_new_files

    def interrupted(writer: DatasetWriter) -> None:
        if writer.num_episodes == 1:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while the 2nd episode is being saved
        original(writer)

    monkeypatch.setattr(DatasetWriter, "_continue_in_new_files", interrupted)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    run_script(env, [["s"], ["."]])
    with pytest.raises(KeyboardInterrupt):
        run_script(env, [["s"]])
    assert rec.saved_episodes == 2
    env.close()
    path = the_dataset(tmp_path)
    assert check_loads(path, 2, 2) == 2
    assert not (path / ".embodichain_staging").exists()


@pytest.mark.parametrize("mode", ["die_in_create", "die_in_first_save", "die_in_first_publish"])
def test_a_kill_before_the_first_episode_is_saved_leaves_an_incomplete_folder(
    make_env, tmp_path: Path, mode: str, caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture
) -> None:
    import logging

    from lerobot_helpers import arm_cfg, recorder_cfg, reset, run_script

    from embodichain_lerobot.cli import main as dataset_cli
    from embodichain_lerobot.folders import IncompleteDatasetError, folder_status

    rec = Recording(mode, tmp_path)
    out = rec.finish(sig=None)
    assert rec.proc.returncode == -signal.SIGKILL
    assert "COMMITTED" not in out
    path = the_dataset(tmp_path)
    has_info = (path / "meta" / "info.json").is_file()
    assert has_info == (mode != "die_in_create")
    assert (path / ".embodichain_staging").is_dir()
    assert (path / "data").is_dir() == (mode == "die_in_first_publish")  # partial data of the 1st episode
    assert folder_status(path).removable
    # `embodichain dataset info` and the loaders refuse it: it is never handed to lerobot
    assert dataset_cli(["info", str(path)]) == 2
    assert f"{path} is an incomplete recording, not a dataset" in capsys.readouterr().err
    with pytest.raises(IncompleteDatasetError, match="holds no episode"):
        load(path)
    # the next run of the recorder with the same save_path removes it, naming it, and records afresh
    with caplog.at_level(logging.WARNING, logger="embodichain_lerobot"):
        env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path)))
    assert f"removed incomplete dataset folder {path}" in caplog.text
    assert not path.exists()
    reset(env)
    run_script(env, [["."], ["s"]])
    env.close()
    assert the_dataset(tmp_path) == path
    assert check_loads(path, 1, 1) == 1
    assert not (path / ".embodichain_recording").exists()
