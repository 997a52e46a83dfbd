"""``embodichain_core.gym_utils``: the launcher arguments the seed tutorial uses."""

from __future__ import annotations

import argparse
import itertools

import pytest

from embodichain_core.gym_utils import add_env_launcher_args_to_parser, episode_loop, launcher_overrides


def parse(*argv: str, **kwargs) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_env_launcher_args_to_parser(parser, **kwargs)
    return parser.parse_args(list(argv))


def test_defaults_are_embodichain_s() -> None:
    args = parse()
    assert (args.num_envs, args.device, args.headless, args.renderer) == (1, "cpu", False, "auto")
    assert (args.gym_config, args.max_episodes, args.seed) == ("", None, None)
    assert not (args.preview)
    assert not (args.filter_visual_rand)
    assert not (args.filter_dataset_saving)
    assert launcher_overrides(args) == {}


def test_only_given_values_override_a_config() -> None:
    args = parse("--num_envs", "1", "--headless", "--renderer", "rt", "--max_episodes", "3", "--seed", "7")
    assert launcher_overrides(args) == {"num_envs": 1, "headless": True, "renderer": "rt", "max_episodes": 3, "seed": 7}
    assert launcher_overrides(parse("--preview")) == {"filter_dataset_saving": True}
    assert launcher_overrides(parse("--filter_visual_rand", "--device", "cuda")) == {
        "filter_visual_rand": True,
        "device": "cuda",
    }


def test_renderer_choices_and_required_gym_config(capsys) -> None:
    with pytest.raises(SystemExit):
        parse("--renderer", "raytracer")
    with pytest.raises(SystemExit):
        parse(require_gym_config=True)
    assert parse("--gym_config", "cfg.json", require_gym_config=True).gym_config == "cfg.json"


def test_episode_loop() -> None:
    assert list(episode_loop(parse("--max_episodes", "2"))) == [0, 1]
    assert list(episode_loop(parse("--max_episodes", "0"))) == []
    assert list(itertools.islice(episode_loop(parse()), 1000)) == list(range(1000))
