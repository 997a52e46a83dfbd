"""``embodichain run-env`` (embodichain_core.cli.run_env)."""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any, Callable, Iterator

import gymnasium as gym
import pytest
import torch

from scenes import ARM_MJCF

from embodichain_core.cli import run_env
from embodichain_core.cli.main import main as embodichain
from embodichain_core.envs import EmbodiedEnv, EmbodiedEnvCfg
from embodichain_core.envs.registration import register_env
from embodichain_core.managers.functor import DatasetFunctor
from embodichain_core.sim.cfg import RobotCfg
from embodichain_core.utils.configclass import configclass

SAVED: list[int] = []


class PlainTask(EmbodiedEnv):
    """A task with the env's default behaviour (random actions in run-env)."""


@configclass
class CompleteCfg(EmbodiedEnvCfg):
    """A task config that needs no file."""

    robot: RobotCfg = RobotCfg(uid="arm", mjcf=ARM_MJCF)
    num_envs: int = 2
    max_episode_steps: int = 3
    verbose: bool = False


class DefaultCfgTask(EmbodiedEnv):
    cfg_cls = CompleteCfg


class DemoTask(EmbodiedEnv):
    """Data generation: a 3-step demo that fails on its first attempt, succeeds afterwards."""

    def create_demo_action_list(self) -> list:
        self.demo_calls = getattr(self, "demo_calls", 0) + 1
        return [torch.zeros(self.action_space.shape)] * 3

    def compute_task_state(self, **kwargs: Any) -> tuple:
        success = (self.elapsed_steps >= 3) & (getattr(self, "demo_calls", 0) >= 2)
        return success, torch.zeros_like(success), {}


class Recorder(DatasetFunctor):
    """Remembers committed env ids; ``finalize`` returns a fake path."""

    def __call__(self, env: Any, env_ids: Any, out: str = "") -> None:
        SAVED.extend(int(i) for i in env_ids)

    def finalize(self) -> str:
        return self.cfg.params["out"]


@pytest.fixture
def task() -> Iterator[Callable[[type], str]]:
    """``task(cls) -> id``: registers ``cls`` under a fresh id, removed after the test."""
    ids: list[str] = []

    def register(cls: type) -> str:
        uid = f"RunEnvTest{uuid.uuid4().hex[:8]}-v0"
        register_env(uid)(cls)
        ids.append(uid)
        return uid

    yield register
    for uid in ids:
        gym.registry.pop(uid, None)


def write_config(path: Path, task_id: str, **top: Any) -> Path:
    data = {
        "id": task_id,
        "num_envs": 2,
        "max_episode_steps": 4,
        "max_episodes": 2,
        "env": {"seed": 0, "verbose": False},
        "robot": {"uid": "arm", "mjcf": ARM_MJCF},
        "rigid_object": [{"uid": "cube", "init_pos": [0.4, 0, 0.1]}],
    }
    data.update(top)
    path.write_text(json.dumps(data))
    return path


def test_demo_runs_and_prints_a_summary(capsys: pytest.CaptureFixture) -> None:
    code = embodichain(["run-env", "--max_episodes", "2", "--max_steps", "3", "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    assert "run-env summary: EmbodiChainDemo-v0" in out
    assert "episodes     2 (2 env(s))" in out
    assert "successes    0/2" in out
    assert "env-steps/s" in out
    assert "wall time" in out
    assert "no dataset recorder" in out
    assert "actions      0 env-step(s) outside the action space (clipped)" in out  # random actions: inside
    assert "Environment initialized" not in out  # --quiet


def test_the_start_up_summary_names_the_backend(capsys: pytest.CaptureFixture) -> None:
    assert embodichain(["run-env", "--max_episodes", "1", "--max_steps", "2"]) == 0
    out = capsys.readouterr().out
    assert "Environment initialized" in out
    assert "│ Backend  mujoco_batch (CPU threads: " in out


def test_num_envs_overrides_only_when_given(tmp_path: Path, task: Callable) -> None:
    config = write_config(tmp_path / "c.json", task(PlainTask))
    given = run_env.prepare(run_env.build_parser().parse_args(["--gym_config", str(config), "--num_envs", "3"]))
    absent = run_env.prepare(run_env.build_parser().parse_args(["--gym_config", str(config)]))
    assert (given.cfg.num_envs, absent.cfg.num_envs) == (3, 2)
    assert absent.cfg.sim_cfg.headless is True
    assert absent.extras["max_episodes"] == 2
    flags = run_env.prepare(run_env.build_parser().parse_args([str(config), "--seed", "5", "--max_steps", "9"]))
    assert (flags.cfg.seed, flags.cfg.max_episode_steps, absent.cfg.seed) == (5, 9, 0)


def test_config_file_runs_with_cli_num_envs(tmp_path: Path, task: Callable, capsys: pytest.CaptureFixture) -> None:
    config = write_config(tmp_path / "c.yaml", task(PlainTask))
    config.write_text(config.read_text())  # JSON is valid YAML
    assert run_env.main(["--gym_config", str(config), "--num_envs", "3", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "episodes     3 (3 env(s))" in out  # the 3 envs end together at step 4


def test_preview(tmp_path: Path, task: Callable, capsys: pytest.CaptureFixture) -> None:
    config = write_config(tmp_path / "c.json", task(PlainTask))
    assert run_env.main(["--gym_config", str(config), "--preview"]) == 0
    out = capsys.readouterr().out
    assert "observation space (per env):" in out
    assert "qpos: Box shape=(3,)" in out
    assert "action space (per env):" in out
    assert "info keys after one step:" in out
    assert "success" in out
    assert "run-env summary" not in out


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d["env"].update(evnts={}), "env.evnts: unknown env key 'evnts'. Did you mean 'events'?"),
        (
            lambda d: d["env"].update(events={"push": {"func": "test_run_env_cli:no_such_event"}}),
            "env.events.push.func: cannot import",
        ),
        (lambda d: d.update(id="RunEnvTestNope-v0"), "id: unknown task 'RunEnvTestNope-v0'"),
    ],
)
def test_config_errors_exit_2_with_the_path(
    tmp_path: Path, task: Callable, capsys: pytest.CaptureFixture, mutate: Any, message: str
) -> None:
    config = write_config(tmp_path / "c.json", task(PlainTask))
    data = json.loads(config.read_text())
    mutate(data)
    config.write_text(json.dumps(data))
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"config error in {config}" in err
    assert message in err
    assert "Traceback" not in err


def test_missing_config_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert run_env.main(["--gym_config", str(tmp_path / "nope.yaml")]) == 2
    assert "cannot read config file" in capsys.readouterr().err


def test_bare_task_id_uses_the_env_default_cfg(task: Callable, capsys: pytest.CaptureFixture) -> None:
    uid = task(DefaultCfgTask)
    assert run_env.main([uid, "--max_episodes", "4", "--quiet", "--headless"]) == 0
    assert "episodes     4 (2 env(s))" in capsys.readouterr().out
    plan = run_env.prepare(run_env.build_parser().parse_args([uid, "--num_envs", "1", "--seed", "3"]))
    assert plan.cfg is None
    assert plan.make_kwargs == {"num_envs": 1, "seed": 3}
    assert run_env.main([uid, "--num_envs", "1", "--max_episodes", "1", "--renderer", "rt", "--quiet"]) == 0
    assert "episodes     1 (1 env(s))" in capsys.readouterr().out


def test_bare_task_without_default_cfg_needs_a_config(task: Callable, capsys: pytest.CaptureFixture) -> None:
    assert run_env.main([task(PlainTask), "--renderer", "rt"]) == 2
    assert "pass --gym_config to use --renderer" in capsys.readouterr().err


def test_demo_action_list_retries_failed_attempts(
    tmp_path: Path, task: Callable, capsys: pytest.CaptureFixture
) -> None:
    dataset = {"rec": {"func": f"{__name__}:Recorder", "params": {"out": str(tmp_path / "data")}}}
    config = write_config(
        tmp_path / "c.json",
        task(DemoTask),
        max_episode_steps=10,
        max_episodes=2,
        env={"seed": 0, "verbose": False, "dataset": dataset},
    )
    SAVED.clear()
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    out = capsys.readouterr().out
    # the failed first attempt counts in the success rate; both envs' retries were saved
    assert "successes    2/4 (50.0%)" in out
    assert "discarded    2 failed demo episode(s)" in out
    assert "saved        2 episode(s)\n" in out
    assert "failed       2 demo episode(s) did not succeed" in out
    assert "lost" not in out
    assert f"data         {tmp_path / 'data'}" in out
    assert sorted(SAVED) == [0, 1]  # the successful attempt of both envs was committed once
    assert run_env.main(["--gym_config", str(config), "--quiet", "--filter_dataset_saving"]) == 0
    assert "no dataset recorder" in capsys.readouterr().out
