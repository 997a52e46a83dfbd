"""One definition of the env launcher arguments: ``embodichain run-env`` and a script using
``embodichain_core.gym_utils.add_env_launcher_args_to_parser`` accept the same flags, with the
same defaults and renderer choices, and a flag that is not given never overrides a config."""

from __future__ import annotations

import argparse

import pytest

from embodichain_core.cli import run_env
from embodichain_core.gym_utils import (
    LAUNCHER_DEFAULTS,
    RENDERERS,
    add_env_launcher_args_to_parser,
)

#: Arguments only ``run-env`` has (beyond the shared launcher arguments).
RUN_ENV_ONLY = {"help", "task", "max_steps", "quiet"}


def script_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    add_env_launcher_args_to_parser(parser)
    return parser


def actions(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {a.dest: a for a in parser._actions}


def test_run_env_and_scripts_share_every_launcher_argument() -> None:
    script, cli = actions(script_parser()), actions(run_env.build_parser())
    assert set(cli) - RUN_ENV_ONLY == set(script) - {"help"} == set(LAUNCHER_DEFAULTS)
    for dest in LAUNCHER_DEFAULTS:
        ours, theirs = script[dest], cli[dest]
        assert ours.option_strings == theirs.option_strings, dest
        assert ours.default == theirs.default == LAUNCHER_DEFAULTS[dest], dest
        assert (ours.type, ours.choices, ours.nargs, ours.help) == (
            theirs.type,
            theirs.choices,
            theirs.nargs,
            theirs.help,
        ), dest
    assert script["renderer"].choices == cli["renderer"].choices == RENDERERS


def test_no_flag_overrides_the_config() -> None:
    args = run_env.build_parser().parse_args([])
    assert run_env.overrides_from_args(args) == {}
    assert (args.num_envs, args.device, args.renderer, args.gym_config) == (1, "cpu", "auto", "")


def test_given_flags_become_overrides() -> None:
    args = run_env.build_parser().parse_args(
        [
            "Task-v0",
            "--num_envs",
            "1",
            "--device",
            "cpu",
            "--renderer",
            "auto",
            "--headless",
            "--seed",
            "0",
            "--max_episodes",
            "2",
            "--max_steps",
            "9",
            "--quiet",
            "--filter_visual_rand",
        ]
    )
    # values equal to the defaults are still overrides: they were given
    assert run_env.overrides_from_args(args) == {
        "num_envs": 1,
        "device": "cpu",
        "renderer": "auto",
        "headless": True,
        "seed": 0,
        "max_episodes": 2,
        "filter_visual_rand": True,
        "max_episode_steps": 9,
        "verbose": False,
    }
    assert args.task == "Task-v0"
    assert run_env.overrides_from_args(run_env.build_parser().parse_args(["--preview"])) == {
        "filter_dataset_saving": True
    }


@pytest.mark.parametrize("parser", [script_parser, run_env.build_parser])
def test_both_reject_an_unknown_renderer(parser, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        parser().parse_args(["--renderer", "raytracer"])
    assert exit_info.value.code == 2
    assert "invalid choice: 'raytracer'" in capsys.readouterr().err
