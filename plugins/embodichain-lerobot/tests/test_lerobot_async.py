"""AsyncLeRobotRecorder: same dataset as the synchronous recorder (with the writer
process, colour streamed to it while the episodes run, and with the worker thread),
commits that do not wait for writing, worker errors at the next call and at finalize,
no calls after finalize."""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from lerobot_helpers import arm_cfg, as_np, have_sensors, load, recorder_cfg, reset, run_script, stereo_camera

from embodichain_lerobot.async_recorder import AsyncLeRobotRecorder
from embodichain_lerobot.recorder import LeRobotRecorder
from embodichain_lerobot.writer_process import WriterProcessError

SCRIPT = [[".", "."], ["s", "."], [".", "f"], [".", "."], ["s", "s"], [".", "."]]


def run(make_env: Any, tmp_path: Path, func: str, cameras: bool = False, **params: Any) -> Any:
    sensors = [stereo_camera(32, 24, depth=False, mask=False)] if cameras else None
    folder = tmp_path / f"{func}{len(params)}"
    env = make_env(arm_cfg(2, dataset=recorder_cfg(folder, func=func, **params), sensors=sensors))
    reset(env)
    run_script(env, SCRIPT)
    env.close()
    return load(env.dataset_manager.finalize()[0])


def test_async_writes_the_same_dataset_as_sync(make_env: Any, tmp_path: Path) -> None:
    sync, asyn = run(make_env, tmp_path, "LeRobotRecorder"), run(make_env, tmp_path, "AsyncLeRobotRecorder")
    assert asyn.num_episodes == sync.num_episodes == 3
    assert len(asyn) == len(sync)
    assert list(asyn.meta.episodes["length"]) == list(sync.meta.episodes["length"])
    for i in range(len(sync)):
        a, s = asyn[i], sync[i]
        for key in ("observation.state", "observation.qf", "action", "episode_index", "frame_index"):
            np.testing.assert_array_equal(as_np(a[key]), as_np(s[key]))
        assert a["task"] == s["task"]


@pytest.mark.skipif(not have_sensors(), reason="needs embodichain-sensors")
@pytest.mark.parametrize(
    "func, writer_process",
    [("AsyncLeRobotRecorder", True), ("AsyncLeRobotRecorder", False), ("LeRobotRecorder", True)],
)
def test_async_videos_match_sync(make_env: Any, tmp_path: Path, func: str, writer_process: bool) -> None:
    """With the writer process, colour is streamed while the episodes run (envs that fail,
    succeed and reset at different steps); the decoded videos match the synchronous recorder's."""
    sync = run(make_env, tmp_path, "LeRobotRecorder", cameras=True, use_videos=True)
    asyn = run(make_env, tmp_path, func, cameras=True, use_videos=True, writer_process=writer_process)
    assert list(asyn.meta.episodes["length"]) == list(sync.meta.episodes["length"]) == [2, 3, 2]
    for i in range(len(sync)):
        for key in ("observation.images.head", "observation.images.head_right"):
            a, s = as_np(asyn[i][key]), as_np(sync[i][key])
            assert np.abs(a - s).mean() < 0.02, (i, key)  # the same frames (lossy codec, same settings)
        np.testing.assert_array_equal(as_np(asyn[i]["observation.state"]), as_np(sync[i]["observation.state"]))


class _Gate:
    """Makes ``LeRobotRecorder._write_now`` wait until released."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch):
        self.release, self.entered = threading.Event(), threading.Event()
        original = LeRobotRecorder._write_now

        def gated(rec: Any, episode: Any) -> None:
            self.entered.set()
            assert self.release.wait(30)
            original(rec, episode)

        monkeypatch.setattr(LeRobotRecorder, "_write_now", gated)


def test_commits_do_not_wait_for_writing_and_finalize_drains(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    gate = _Gate(monkeypatch)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path, func="AsyncLeRobotRecorder", writer_process=False)))
    rec = env.dataset_manager.get_functor("rec")
    assert isinstance(rec, AsyncLeRobotRecorder)
    reset(env)
    run_script(env, [["s"], ["."], ["s"], ["."], ["."]])  # two commits while the worker is blocked
    assert gate.entered.wait(30)
    assert rec.saved_episodes == 0
    assert rec.pending_episodes >= 1
    gate.release.set()
    path = rec.finalize()  # drains the queue first; the live 2-frame episode is dropped
    assert rec.saved_episodes == 2
    assert load(path).num_episodes == 2
    with pytest.raises(RuntimeError, match="finalized"):
        rec(env, torch.tensor([0]))


GATED_WRITER = """
import os
import time

from embodichain_lerobot.writer import DatasetWriter

_original = DatasetWriter.write_episode


def write_episode(self, frames, record):
    while not os.path.exists({gate!r}):  # the test opens the gate
        time.sleep(0.02)
    return _original(self, frames, record)


DatasetWriter.write_episode = write_episode
"""


def test_commits_to_the_writer_process_do_not_wait_and_finalize_drains(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    hook, gate = tmp_path / "hook", tmp_path / "gate"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(GATED_WRITER.format(gate=str(gate)))  # runs in the writer process
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(hook), os.environ.get("PYTHONPATH")])))
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path / "data", func="AsyncLeRobotRecorder")))
    rec = env.dataset_manager.get_functor("rec")
    assert rec.params.writer_process is True  # the async recorder's default
    reset(env)
    run_script(env, [["s"], ["."], ["s"], ["."], ["."]])  # two commits while the writer process waits
    time.sleep(0.5)
    assert rec.saved_episodes == 0
    assert rec.pending_episodes == 2
    gate.touch()
    path = rec.finalize()  # waits for both; the live 2-frame episode is dropped
    assert rec.saved_episodes == 2
    assert load(path).num_episodes == 2
    with pytest.raises(RuntimeError, match="finalized"):
        rec(env, torch.tensor([0]))


def test_a_writer_process_that_cannot_start_fails_the_recording_clearly(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text("import sys\nsys.modules['lerobot'] = None  # lerobot is not importable\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(hook), os.environ.get("PYTHONPATH")])))
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path / "data", func="AsyncLeRobotRecorder")))
    reset(env)
    with pytest.raises(RuntimeError, match=r"the dataset writer process exited \(code 1; its own error"):
        run_script(env, [["s"], ["."]])  # raised here if the child is already gone, else at close
        env.close()
    with contextlib.suppress(RuntimeError):  # raised again if the step raised first
        env.dataset_manager.finalize()
    assert list((tmp_path / "data").iterdir()) == []  # the reserved dataset folder is not left behind


class _CountedPopen(subprocess.Popen):
    """``subprocess.Popen`` that notes each dataset writer process it starts."""

    started: list = []

    def __init__(self, args: Any, *more: Any, **kwargs: Any):
        if "embodichain_lerobot.writer_child" in list(args):
            self.started.append(args)
        super().__init__(args, *more, **kwargs)


@pytest.mark.parametrize(
    "func, params",
    [("AsyncLeRobotRecorder", {}), ("LeRobotRecorder", {"writer_process": True, "use_videos": True})],
)
def test_the_writer_process_starts_with_recording_and_a_recorder_without_commits_leaves_nothing(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, func: str, params: dict
) -> None:
    monkeypatch.setattr(_CountedPopen, "started", [])
    monkeypatch.setattr(subprocess, "Popen", _CountedPopen)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path / "data", func=func, **params)))
    rec = env.dataset_manager.get_functor("rec")
    assert rec.params.writer_process is True
    assert _CountedPopen.started == []  # building the env (to check a config, say) starts no child
    reset(env)
    assert len(_CountedPopen.started) == 1  # recording starts: the child imports lerobot meanwhile
    run_script(env, [["."], ["f"], ["."]])  # a failed episode (discarded) and a live one, no commit
    env.close()
    assert env.dataset_manager.finalize() == [None]
    assert len(_CountedPopen.started) == 1
    assert list((tmp_path / "data").glob("*")) == []  # no dataset folder (save_path itself is not made)


def test_an_env_built_and_closed_starts_no_writer_process(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_CountedPopen, "started", [])
    monkeypatch.setattr(subprocess, "Popen", _CountedPopen)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path / "data", func="AsyncLeRobotRecorder")))
    env.close()
    assert env.dataset_manager.finalize() == [None]
    assert _CountedPopen.started == []


def test_a_writer_process_that_cannot_be_launched_names_the_param_to_change(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_more_processes(*args: Any, **kwargs: Any) -> Any:
        raise OSError(errno.EAGAIN, "Resource temporarily unavailable")

    monkeypatch.setattr(subprocess, "Popen", no_more_processes)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path / "data", func="AsyncLeRobotRecorder")))
    with pytest.raises(
        WriterProcessError,
        match=r"cannot start the dataset writer process \(.* -m embodichain_lerobot"
        r"\.writer_child\): .*Resource temporarily unavailable; .*params\.writer_process to false",
    ):
        reset(env)  # the first recorded observation starts it
    env.close()
    assert env.dataset_manager.finalize() == [None]
    assert list((tmp_path / "data").glob("*")) == []  # no dataset folder is made


def test_episodes_are_copies_unaffected_by_later_steps(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    gate = _Gate(monkeypatch)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path, func="AsyncLeRobotRecorder", writer_process=False)))
    obs = reset(env)
    first = obs["robot"]["qpos"][0].clone()
    run_script(env, [["."], ["s"]])
    run_script(env, [["."]] * 5)  # the env moves on while the committed episode waits
    gate.release.set()
    env.close()
    ds = load(env.dataset_manager.finalize()[0])
    np.testing.assert_array_equal(as_np(ds[0]["observation.state"]), first.numpy())
    assert len(ds) == 2


def test_worker_errors_surface_at_the_next_call_and_at_finalize(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(rec: Any, episode: Any) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(LeRobotRecorder, "_write_now", broken)
    env = make_env(arm_cfg(1, dataset=recorder_cfg(tmp_path, func="AsyncLeRobotRecorder", writer_process=False)))
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    run_script(env, [["s"]])
    rec._queue.join()
    with pytest.raises(RuntimeError, match="disk full"):
        run_script(env, [["."]])
    run_script(env, [["s"]])  # the first error was reported; this commit fails on the worker too
    with pytest.raises(RuntimeError, match=r"AsyncLeRobotRecorder: writing 1 episode\(s\) failed.*disk full"):
        env.close()  # each error is raised once: here the second one
    assert rec.finalize() is None  # idempotent after the failure


def test_construction_only_params_are_accepted(make_env: Any, tmp_path: Path) -> None:
    env = make_env(
        arm_cfg(
            1,
            dataset=recorder_cfg(tmp_path, func="AsyncLeRobotRecorder", max_pending_episodes=2, image_writer_threads=2),
        )
    )
    rec = env.dataset_manager.get_functor("rec")
    assert rec.params.max_pending_episodes == 2
    assert rec.params.image_writer_threads == 2
    assert rec._queue.maxsize == 2
