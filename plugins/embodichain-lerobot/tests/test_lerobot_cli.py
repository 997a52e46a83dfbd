"""``embodichain dataset info`` and ``embodichain dataset preview`` (through the
``embodichain`` entry point), and the plugin's registrations."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from lerobot_helpers import ScriptedEnv, arm_cfg, have_sensors, recorder_cfg, reset, run_script, stereo_camera

from embodichain_core.cli.main import main as embodichain
from embodichain_lerobot import preview


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two episodes (3 and 2 frames) of two envs, with a stereo camera when the sensors plugin is installed."""
    root = tmp_path_factory.mktemp("cli")
    sensors = [stereo_camera(40, 30)] if have_sensors() else []
    env = ScriptedEnv(arm_cfg(2, dataset=recorder_cfg(root), sensors=sensors))
    reset(env)
    run_script(env, [[".", "."], [".", "s"], ["s", "."]])
    env.close()
    return Path(env.dataset_manager.finalize()[0])


def test_plugin_registers_the_recorders_and_the_command() -> None:
    from embodichain_core.plugins import get_registry, load_plugins

    load_plugins()
    functors = get_registry("functors")
    for name in ("LeRobotRecorder", "AsyncLeRobotRecorder"):
        assert functors.find(name).meta["kind"] == "dataset"
    assert get_registry("commands").find("dataset").target == "embodichain_lerobot.cli:main"


def test_core_and_plugin_loading_import_no_lerobot() -> None:
    code = (
        "import sys, embodichain_core.envs, embodichain_core.managers, embodichain_lerobot\n"
        "from embodichain_core.plugins import load_plugins; load_plugins()\n"
        "assert not [m for m in sys.modules if m.split('.')[0] == 'lerobot'], 'lerobot imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_building_an_env_with_a_recorder_imports_no_lerobot(tmp_path: Path) -> None:
    code = (
        "import sys\n"
        "from lerobot_helpers import ScriptedEnv, arm_cfg, recorder_cfg, reset, run_script\n"
        f"env = ScriptedEnv(arm_cfg(1, dataset=recorder_cfg({str(tmp_path)!r})))\n"
        "assert 'lerobot.datasets.lerobot_dataset' not in sys.modules, 'imported during the build'\n"
        "reset(env)\n"
        "run_script(env, [['s']])\n"
        "assert env.dataset_manager.get_functor('rec').saved_episodes == 1\n"
        "env.close()\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=Path(__file__).parent)


def test_info_lists_episodes_frames_features_fps_and_tasks(dataset: Path, capsys: pytest.CaptureFixture) -> None:
    assert embodichain(["dataset", "info", str(dataset)]) == 0
    out = capsys.readouterr().out
    assert "episodes  2 (length min 2, mean 2.5, max 3)" in out
    assert "frames    5" in out
    assert "25 fps" in out
    assert "robot_type Arm7" in out
    assert "'Push the cube'" in out
    assert "observation.state" in out
    assert "success   2/2" in out
    assert "  action" in out
    assert "float32  (7,)" in out
    rows = out.split("episode_seed\n")[-1].splitlines()  # per episode, without --episodes
    assert [r.split()[:3] for r in rows] == [["0", "2", "yes"], ["1", "3", "yes"]]
    if have_sensors():
        assert "observation.images.head_right" in out
        assert "observation.depth.head" in out
        assert "image    (30, 40, 3)" in out
    assert embodichain(["dataset", "info", str(dataset), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["episodes"] == 2
    assert summary["episode_lengths"] == [2, 3]
    assert summary["fps"] == 25
    assert summary["features"]["action"]["shape"] == [7]
    assert summary["tasks"] == ["Push the cube"]
    assert summary["episode_successes"] == [True, True]


def test_info_lists_at_most_20_episodes_without_the_flag(dataset: Path) -> None:
    from embodichain_lerobot.reading import dataset_summary, format_episodes

    summary = dataset_summary(dataset)
    summary["episode_lengths"] = summary["episode_lengths"] * 15
    lines = format_episodes(summary, 20).splitlines()
    assert len(lines) == 22
    assert "10 more episode(s) (--episodes lists every one)" in lines[-1]
    assert len(format_episodes(summary).splitlines()) == 31


@pytest.mark.parametrize("fmt", ["png", "mp4"])
def test_preview_writes_cameras_and_a_state_action_plot(
    dataset: Path, tmp_path: Path, fmt: str, capsys: pytest.CaptureFixture
) -> None:
    assert (
        embodichain(["dataset", "preview", str(dataset), "--episode", "1", "--out", str(tmp_path), "--format", fmt])
        == 0
    )
    written = [Path(line) for line in capsys.readouterr().out.split()]
    assert all(p.is_file() and p.stat().st_size > 0 for p in written)
    assert any(p.name.endswith("_ep001_state_action.png") for p in written)
    if have_sensors():
        (cams,) = [p for p in written if "_cameras." in p.name]
        assert cams.suffix == f".{fmt}"
        if fmt == "png":
            assert Image.open(cams).size[0] > 2 * 96  # the sampled frames side by side


def test_the_state_action_plot_has_labelled_axes(dataset: Path, tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    from embodichain_lerobot.reading import load_dataset

    seen: list = []
    real_savefig = plt.Figure.savefig

    def spy(fig: "plt.Figure", *a: object, **kw: object) -> None:
        seen.extend((ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes)
        real_savefig(fig, *a, **kw)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(plt.Figure, "savefig", spy)
        path = preview.plot_state_action(load_dataset(dataset, episodes=[0]), tmp_path / "plot.png", "t")
    assert Image.open(path).size == (900, 600)  # two panels, 9 x 3 inches each at 100 dpi
    assert seen == [("", "observation.state"), ("time (s)", "action")]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["preview", "{ds}", "--episode", "5"], "episode 5 is out of range: the dataset has 2 episode(s)"),
        (["info", "{tmp}"], "is not a LeRobot dataset (no meta/info.json)"),
        (["preview", "{tmp}", "--episode", "0"], "is not a LeRobot dataset"),
    ],
)
def test_errors_exit_2_with_a_message(
    dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture, argv: list, message: str
) -> None:
    argv = [a.format(ds=dataset, tmp=tmp_path) for a in argv]
    assert embodichain(["dataset", *argv]) == 2
    assert message in capsys.readouterr().err


def test_help_reaches_the_command_parser(capsys: pytest.CaptureFixture) -> None:
    assert embodichain(["dataset", "preview", "--help"]) == 0
    assert "--episode N" in capsys.readouterr().out


def test_a_killed_recording_is_reported(dataset: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    import shutil

    copy = tmp_path / dataset.name
    shutil.copytree(dataset, copy)
    (copy / ".embodichain_staging").mkdir()
    assert embodichain(["dataset", "info", str(copy)]) == 0
    assert "the recording was not finalized" in capsys.readouterr().out
