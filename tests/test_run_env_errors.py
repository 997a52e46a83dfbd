"""``embodichain run-env`` error reporting: a functor that raises is named by its config
path with the traceback, the env is closed (recorders finalized) and the summary printed;
dataset outputs are checked by the recorder's ``preflight`` before the env is built."""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any, Iterator

import gymnasium as gym
import pytest

from scenes import ARM_MJCF

from embodichain_core.cli import run_env
from embodichain_core.config.errors import ConfigError
from embodichain_core.envs import EmbodiedEnv
from embodichain_core.envs.registration import register_env
from embodichain_core.managers.functor import DatasetFunctor

BUILT: list[str] = []
FINALIZED: list[str] = []


class CountingTask(EmbodiedEnv):
    """A plain task that remembers it was built."""

    def __init__(self, *args: Any, **kwargs: Any):
        BUILT.append(type(self).__name__)
        super().__init__(*args, **kwargs)


def drive_damping(env: Any, env_ids: Any, fail_on_call: int = 2) -> None:
    """An event functor that raises on its ``fail_on_call``-th call."""
    env.damping_calls = getattr(env, "damping_calls", 0) + 1
    if env.damping_calls >= fail_on_call:
        raise ValueError("damping must be finite, got nan")


class FinalizingRecorder(DatasetFunctor):
    """Saves nothing; ``finalize`` is recorded and returns ``out``."""

    def __call__(self, env: Any, env_ids: Any, out: str = "") -> None:
        pass

    def finalize(self) -> str:
        FINALIZED.append(self.cfg.params["out"])
        return self.cfg.params["out"]


class CheckedRecorder(FinalizingRecorder):
    """Its ``preflight`` refuses every output folder."""

    @classmethod
    def preflight(cls, params: dict, path: str) -> None:
        raise ConfigError(f"{path}.params.out", f"dataset folder {params['out']} is not writable")


@pytest.fixture
def task_id() -> Iterator[str]:
    uid = f"RunEnvErrors{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(CountingTask)
    BUILT.clear()
    FINALIZED.clear()
    yield uid
    gym.registry.pop(uid, None)


def write_config(path: Path, task: str, events: dict, dataset: dict) -> Path:
    data = {
        "id": task,
        "num_envs": 2,
        "max_episode_steps": 3,
        "max_episodes": 6,
        "env": {"seed": 0, "verbose": False, "events": events, "dataset": dataset},
        "robot": {"uid": "arm", "mjcf": ARM_MJCF},
    }
    path.write_text(json.dumps(data))
    return path


def recorder(cls: str, out: Path) -> dict:
    return {"rec": {"func": f"{__name__}:{cls}", "params": {"out": str(out)}}}


def damping_event(mode: str, fail_on_call: int) -> dict:
    return {
        "drive_damping": {"func": f"{__name__}:drive_damping", "mode": mode, "params": {"fail_on_call": fail_on_call}}
    }


def test_a_functor_error_names_the_functor_prints_the_traceback_and_the_summary(
    tmp_path: Path, task_id: str, capsys: pytest.CaptureFixture
) -> None:
    config = write_config(
        tmp_path / "c.json", task_id, damping_event("reset", 3), recorder("FinalizingRecorder", tmp_path / "data")
    )
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 1
    captured = capsys.readouterr()
    assert "Traceback (most recent call last)" in captured.err
    assert "ValueError: damping must be finite, got nan" in captured.err
    assert "raised in functor env.events.drive_damping" in captured.err  # the traceback's note
    last = captured.err.strip().splitlines()[-1]
    assert last.startswith(
        "embodichain run-env: stopped by an error while running episodes: ValueError in "
        "functor env.events.drive_damping: damping must be finite"
    )
    assert FINALIZED == [str(tmp_path / "data")]  # the env was closed: the recorder finalized
    out = captured.out
    assert f"run-env summary: {task_id}" in out
    assert f"data         {tmp_path / 'data'}" in out
    assert "stopped      early: ValueError in functor env.events.drive_damping" in out


def test_a_functor_error_during_the_build_is_named_too(
    tmp_path: Path, task_id: str, capsys: pytest.CaptureFixture
) -> None:
    config = write_config(tmp_path / "c.json", task_id, damping_event("startup", 1), {})
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err
    assert (
        err.strip()
        .splitlines()[-1]
        .startswith(
            "embodichain run-env: stopped by an error while building the env: ValueError in functor "
            "env.events.drive_damping"
        )
    )


def test_dataset_preflight_fails_before_the_env_is_built(
    tmp_path: Path, task_id: str, capsys: pytest.CaptureFixture
) -> None:
    config = write_config(tmp_path / "c.json", task_id, {}, recorder("CheckedRecorder", tmp_path / "ro"))
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"config error in {config}: env.dataset.rec.params.out: dataset folder {tmp_path / 'ro'}" in err
    assert BUILT == []
    assert "Traceback" not in err
    # --filter_dataset_saving records nothing, so the output is not checked
    assert run_env.main(["--gym_config", str(config), "--quiet", "--filter_dataset_saving"]) == 0
    assert BUILT
    assert FINALIZED == []


@pytest.mark.parametrize("version", [(3, 10), (3, 11)])
def test_the_functor_note_is_added_on_python_3_10_too(
    monkeypatch: pytest.MonkeyPatch, version: tuple[int, int]
) -> None:
    from embodichain_core.managers import manager_base

    monkeypatch.setattr(manager_base.sys, "version_info", version)  # 3.10 has no BaseException.add_note
    err = ValueError("boom")
    manager_base.tag_functor_error(err, "env.events.drive_damping", drive_damping)
    manager_base.tag_functor_error(err, "env.events.outer", drive_damping)  # the innermost functor wins
    assert err.__notes__ == ["raised in functor env.events.drive_damping (drive_damping)"]
    assert manager_base.functor_path_of(err) == "env.events.drive_damping"
