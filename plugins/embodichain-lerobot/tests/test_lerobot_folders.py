"""Folders that hold no episode: what ``dataset info`` says about them matches what the recorder
does with them, and a recording writes nothing into its folder before its recording marker."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from lerobot_helpers import arm_cfg, load, recorder_cfg, reset, run_script

from embodichain_lerobot import env_meta, writer
from embodichain_lerobot.cli import main as dataset_cli
from embodichain_lerobot.folders import clean_incomplete, folder_status


def test_a_folder_without_a_recording_marker_is_reported_as_left_alone_and_is_left_alone(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    path = tmp_path / "arm7_table_push_000"
    (path / "meta").mkdir(parents=True)
    (path / "meta" / "embodichain_env.json").write_text("{}")
    assert dataset_cli(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path} is an incomplete recording, not a dataset (no meta/info.json)" in err
    assert "the recorder leaves it alone: it has no recording marker" in err
    assert "also removes" not in err
    assert not folder_status(path).removable
    assert clean_incomplete(tmp_path, "arm7_table_push") == []
    assert path.is_dir()


@pytest.mark.parametrize("writer_process", [True, False])
def test_the_env_description_is_written_by_the_writer_under_its_marker(
    make_env: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, writer_process: bool
) -> None:
    seen: list = []

    def write_text(root: Any, text: str) -> Path:  # only ever the in-process writer, after its marker
        seen.append((Path(root) / ".embodichain_recording").is_file())
        return original(root, text)

    original = env_meta.write_env_meta_text
    monkeypatch.setattr(writer, "write_env_meta_text", write_text)
    monkeypatch.setattr(env_meta, "write_env_meta_text", None)  # the recorder itself writes nothing
    cfg = arm_cfg(1, dataset=recorder_cfg(tmp_path, func="AsyncLeRobotRecorder", writer_process=writer_process))
    env = make_env(cfg)
    reset(env)
    run_script(env, [["."], ["s"]])
    env.close()
    (path,) = [Path(p) for p in env.dataset_manager.finalize()]
    assert seen == ([] if writer_process else [True])  # a writer process writes it in the child
    assert env_meta.read_env_meta(path)["num_envs"] == 1
    assert load(path).num_episodes == 1
