"""Kill tests of the writer process: every episode counted as saved loads with lerobot's
``LeRobotDataset`` after a ``SIGKILL`` of the recording process (with episodes queued in
the writer process), a ``SIGKILL`` of the writer process, and a ``SIGTERM`` of ``run-env``.

The timing is set by the writer process's test gate (``EMBODICHAIN_WRITER_TEST_GATE``, a
file holding how many episodes it may write), never by sleeps: each kill lands while a
known number of episodes is saved and more are queued.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Optional

import pytest

from lerobot_helpers import load
from test_lerobot_crash import CHILD, the_dataset
from test_lerobot_run_env import write_config

from embodichain_lerobot.storage import MARKER
from embodichain_lerobot.writer_child import TEST_GATE_ENV

pytestmark = pytest.mark.slow  # each test starts a recording process and its writer process (~10-20 s)
STAGING = ".embodichain_staging"


class Gated:
    """A recording process (``lerobot_crash_child.py churn``) whose writer process writes only
    as many episodes as the gate file allows."""

    def __init__(self, tmp_path: Path, allowed: int, camera: bool = False, params: Optional[dict] = None):
        self.gate, self.save_path = tmp_path / "gate", tmp_path / "data"
        self.open(allowed)
        self.stderr = open(tmp_path / "stderr.txt", "w+")
        env = {**os.environ, TEST_GATE_ENV: str(self.gate)}
        more = [str(int(camera)), json.dumps(params or {})]
        self.proc = subprocess.Popen(
            [sys.executable, str(CHILD), "churn", str(self.save_path), "AsyncLeRobotRecorder", *more],
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            text=True,
            env=env,
        )
        self.seen: dict[str, int] = {"COMMITTED": 0, "SENT": 0, "WRITER": 0}

    def open(self, allowed: int) -> None:
        """Let the writer process write its first ``allowed`` episodes."""
        tmp = self.gate.with_suffix(".tmp")
        tmp.write_text(str(allowed))
        os.replace(tmp, self.gate)

    def wait_for(self, committed: int, sent: int, timeout: float = 180) -> None:
        """Read the child's lines until it has saved ``committed`` and sent ``sent`` episodes."""
        deadline = time.monotonic() + timeout
        while self.seen["COMMITTED"] < committed or self.seen["SENT"] < sent or not self.seen["WRITER"]:
            assert time.monotonic() < deadline, f"the recording did not get there in time: {self.seen}"
            line = self.proc.stdout.readline()
            assert line, f"the recording exited early (code {self.proc.poll()}): {self.errors()}"
            word, _, value = line.partition(" ")
            if word in self.seen:
                self.seen[word] = int(value.split()[0])

    def errors(self) -> str:
        self.stderr.flush()
        self.stderr.seek(0)
        return self.stderr.read()


def _wait_finalized(path: Path, timeout: float = 180) -> None:
    """Wait until the (orphaned) writer process has finalized ``path``: its marker is gone."""
    deadline = time.monotonic() + timeout
    while (path / MARKER).exists():
        assert time.monotonic() < deadline, "the writer process did not finalize the dataset"
        time.sleep(0.05)


def test_a_killed_recording_process_loses_no_episode_it_handed_to_the_writer(tmp_path: Path) -> None:
    rec = Gated(tmp_path, allowed=1)
    rec.wait_for(committed=1, sent=3)  # one saved, at least two more queued in the writer process
    rec.proc.kill()
    rec.proc.wait()
    rec.open(10_000)  # the orphaned writer process may now write what it holds
    path = the_dataset(rec.save_path)
    _wait_finalized(path)
    ds = load(path)
    assert ds.num_episodes >= rec.seen["SENT"] >= 3
    assert len(ds) == sum(int(n) for n in ds.meta.episodes["length"])
    assert not (path / STAGING).exists()
    # the writer process's last word counts what loads, not only what it wrote after the parent died
    said = re.search(
        r"the recording process is gone; (\d+) episode\(s\) are saved in (\S+) \((\d+) of them", rec.errors()
    )
    assert said, rec.errors()
    assert int(said.group(1)) == ds.num_episodes
    assert said.group(2) == str(path)
    assert 1 <= int(said.group(3)) <= ds.num_episodes - 1  # the gate let it write one before the kill


def test_a_killed_writer_process_leaves_every_saved_episode_and_names_the_lost_ones(tmp_path: Path) -> None:
    rec = Gated(tmp_path, allowed=2)
    rec.wait_for(committed=2, sent=3)
    os.kill(rec.seen["WRITER"], signal.SIGKILL)
    out, _ = rec.proc.communicate(timeout=180)
    assert rec.proc.returncode != 0  # the recording stops: its writer is gone
    saved = int(re.search(r"FINALIZED (\d+)", out).group(1))
    path = the_dataset(rec.save_path)
    ds = load(path)
    assert ds.num_episodes == saved == 2
    assert not (path / STAGING).exists()
    assert not (path / MARKER).exists()
    assert re.search(r"\d+ finished episode\(s\) \(env ids \[.*\]\) were not saved", rec.errors())


def _run_env(tmp_path: Path, gate: Path) -> subprocess.Popen:
    config = write_config(tmp_path / "cfg.json", "LeRobotKillDemo-v0", tmp_path / "data", "AsyncLeRobotRecorder")
    data = json.loads(config.read_text())
    data["max_episodes"] = 500
    data["env"]["dataset"]["lerobot"]["params"]["max_pending_episodes"] = 4
    config.write_text(json.dumps(data))
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]);"
        "from test_lerobot_run_env import DemoPush;"
        "from embodichain_core.envs.registration import register_env;"
        "register_env('LeRobotKillDemo-v0')(DemoPush);"
        "from embodichain_core.cli import run_env;"
        "sys.exit(run_env.main(sys.argv[2:]))"
    )
    argv = [sys.executable, "-c", code, str(Path(__file__).parent), "--gym_config", str(config), "--headless"]
    env = {**os.environ, TEST_GATE_ENV: str(gate)}
    return subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def _published(save_path: Path) -> Optional[int]:
    for info in save_path.glob("*/meta/info.json"):
        try:
            return int(json.loads(info.read_text()).get("total_episodes", 0))
        except ValueError:
            return None
    return None


def _run_env_until_two_saved(tmp_path: Path, gate: Path) -> tuple[subprocess.Popen, float]:
    """Start run-env gated at 2 episodes; return it once 2 are published, and the deadline."""
    gate.write_text("2")
    proc = _run_env(tmp_path, gate)
    deadline = time.monotonic() + 180
    while (_published(tmp_path / "data") or 0) < 2:
        assert proc.poll() is None, proc.communicate()[1][-3000:]
        assert time.monotonic() < deadline, "run-env saved no episode in time"
        time.sleep(0.05)
    return proc, deadline


def test_sigterm_closes_run_env_like_ctrl_c_and_its_summary_matches_the_dataset(tmp_path: Path) -> None:
    gate = tmp_path / "gate"
    proc, _ = _run_env_until_two_saved(tmp_path, gate)
    proc.send_signal(signal.SIGTERM)
    gate.write_text("10000")
    out, err = proc.communicate(timeout=180)
    assert proc.returncode == 143, err[-3000:]
    assert "stopped      early: terminated (SIGTERM)" in out
    saved = int(re.search(r"saved\s+(\d+) episode", out).group(1))
    (path,) = [p for p in (tmp_path / "data").iterdir() if p.is_dir()]
    assert load(path).num_episodes == saved >= 2
    assert not (path / MARKER).exists()
    assert not (path / STAGING).exists()


def _writer_of(pid: int) -> int:
    """The pid of the writer process of recording process ``pid``."""
    for entry in Path("/proc").iterdir():
        try:
            stat = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            command = (entry / "cmdline").read_bytes()
        except (OSError, IndexError):
            continue
        if int(stat[1]) == pid and b"embodichain_lerobot.writer_child" in command:
            return int(entry.name)
    raise AssertionError(f"process {pid} has no writer process")


def test_a_dead_writer_reads_as_one_block_and_the_summary_keeps_saved_failed_and_lost_apart(tmp_path: Path) -> None:
    gate = tmp_path / "gate"
    proc, deadline = _run_env_until_two_saved(tmp_path, gate)
    held = Path(f"{gate}.held")
    while not held.exists():  # the writer holds the 3rd finished episode: it is lost with the writer
        assert time.monotonic() < deadline, "the writer never held an episode"
        time.sleep(0.05)
    os.kill(_writer_of(proc.pid), signal.SIGKILL)
    out, err = proc.communicate(timeout=180)
    assert proc.returncode == 1, err[-3000:]
    assert "Traceback" not in err, err[-3000:]  # understood: no traceback, told once
    said = re.findall(r"the dataset writer process exited \(code -9[^\n]*", err)
    assert len(said) == 1, err[-3000:]
    assert "2 episode(s) are saved in" in said[0]
    assert "run the command again" in said[0]
    (path,) = [p for p in (tmp_path / "data").iterdir() if p.is_dir()]
    assert load(path).num_episodes == 2
    assert "saved        2 episode(s)\n" in out, out
    lost = re.search(r"lost\s+(\d+) finished episode\(s\) were not saved", out)
    assert lost, out
    assert f"{lost.group(1)} finished episode(s) (env ids" in said[0], said[0] + out
    assert f"they would have been episodes 2-{1 + int(lost.group(1))} of the dataset" in said[0]
    assert not (path / MARKER).exists()
    assert not (path / STAGING).exists()


def test_a_second_ctrl_c_of_run_env_still_prints_what_is_saved(tmp_path: Path) -> None:
    gate = tmp_path / "gate"
    gate.write_text("2")
    proc = _run_env(tmp_path, gate)
    deadline = time.monotonic() + 180
    while not Path(f"{gate}.held").exists():  # two episodes saved, the 3rd held in the writer
        assert proc.poll() is None, proc.communicate()[1][-3000:]
        assert time.monotonic() < deadline, "the writer never held an episode"
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    closing = ""
    while "closing (committed episodes are kept)" not in closing:  # the close waits for the held writer
        assert time.monotonic() < deadline, closing
        closing += proc.stderr.readline()
    time.sleep(1.0)  # it waits in env.close() for the held writer
    proc.send_signal(signal.SIGINT)
    code = proc.wait(timeout=180)  # its pipes stay open: the orphaned writer process shares them
    gate.write_text("10000")  # the orphaned writer finishes what it holds, then finalizes
    out, err = proc.communicate(timeout=180)
    assert code == 130, err[-3000:]
    assert "interrupted (Ctrl-C) again: stopped closing" in err, err[-3000:]
    assert "Traceback" not in err, err[-3000:]
    assert "saved        2 episode(s)\n" in out, out  # what the dataset held when the summary was printed
    assert "stopped      early: interrupted (Ctrl-C)" in out, out
    (path,) = [p for p in (tmp_path / "data").iterdir() if p.is_dir()]
    _wait_finalized(path)
    assert load(path).num_episodes >= 3
