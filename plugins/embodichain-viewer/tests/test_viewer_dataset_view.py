"""``embodichain dataset view``: a recorded episode re-simulated in the viewer, the recorded
camera frames shown beside the re-rendered ones."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from viewer_helpers import action, demo_env, free_port

from embodichain_core.cli.main import main as embodichain
from embodichain_viewer.dataset_view import view_episode


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("view")
    env = demo_env("none", dataset=root, num_envs=1)
    try:
        env.reset(seed=5)
        for k in range(6):
            env.step(action(env, k))
        env.reset()  # commits the episode
    finally:
        env.close()
    (path,) = [p for p in root.iterdir() if p.is_dir()]
    return path


@pytest.mark.usefixtures("every_step_published")
def test_the_episode_replays_in_the_viewer_with_its_recorded_frames(dataset: Path) -> None:
    sessions = []
    result, _ = view_episode(dataset, 0, "browser", free_port(), speed=0, hold=False, on_open=sessions.append)
    assert result.ok, result.failures
    assert result.frames == 6
    (session,) = sessions
    drawn = session.viewer.last
    assert drawn.step == session.steps == 6
    recorded = {name for name in drawn.images if name.startswith("recorded/")}
    assert recorded  # the recorded camera frames, beside the re-rendered cam/color and cam/depth
    assert {"cam/color", "cam/depth"} <= set(drawn.images)


def test_dataset_view_command(dataset: Path, capsys: pytest.CaptureFixture) -> None:
    argv = ["dataset", "view", str(dataset), "--viewer", "browser", "--port", str(free_port()), "--speed", "0"]
    assert embodichain([*argv, "--exit"]) == 0
    out = capsys.readouterr().out
    assert "[embodichain] viewer: http://localhost:" in out
    assert "episode 0" in out
    assert embodichain([*argv, "--episode", "7", "--exit"]) == 2
    assert "out of range" in capsys.readouterr().err


def test_the_comparison_prints_when_the_replay_ends_and_sigterm_says_goodbye(dataset: Path) -> None:
    """Held open (no --exit): the comparison is out before the viewer is held, and SIGTERM
    closes it with a goodbye and exit status 143."""
    command = [str(Path(sys.executable).parent / "embodichain"), "dataset", "view", str(dataset)]
    command += ["--viewer", "browser", "--port", str(free_port()), "--speed", "0"]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = proc.stdout.readline()  # type: ignore[union-attr]
            if not line:
                break
            lines.append(line)
            if line.startswith("episode replayed; the viewer stays open"):
                break
        assert lines, "dataset view printed nothing"
        assert lines[-1].startswith("episode replayed"), "".join(lines)
        assert any("episode 0" in line for line in lines[:-1]), "".join(lines)  # the comparison, before
        proc.send_signal(signal.SIGTERM)
        rest, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, rest
    assert "dataset view: SIGTERM: the viewer is closed (the comparison is above)" in rest
    assert "Traceback" not in rest
