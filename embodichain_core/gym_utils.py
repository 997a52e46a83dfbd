"""Launcher helpers for env scripts (EmbodiChain's ``lab.gym.utils.gym_utils`` surface).

:func:`add_env_launcher_args_to_parser` adds the standard launcher arguments to a
script's parser. Unlike EmbodiChain, a CLI value overrides a gym config only when it is
given: the parsed namespace keeps EmbodiChain's defaults (``args.num_envs == 1``) and
remembers which arguments were given, and :func:`launcher_overrides` returns only those.

Example:
    >>> import argparse
    >>> parser = argparse.ArgumentParser()
    >>> add_env_launcher_args_to_parser(parser)
    >>> args = parser.parse_args(["--headless", "--num_envs", "2"])
    >>> args.num_envs, args.device, args.renderer, args.max_episodes
    (2, 'cpu', 'auto', None)
    >>> launcher_overrides(args)
    {'num_envs': 2, 'headless': True}
"""

from __future__ import annotations

import argparse
import itertools
from typing import Any, Iterator, Optional

__all__ = ["add_env_launcher_args_to_parser", "launcher_overrides", "episode_loop", "RENDERERS"]

#: Renderer names accepted by ``--renderer`` (EmbodiChain's; all render with MuJoCo here).
RENDERERS = ("auto", "hybrid", "fast-rt", "rt")

#: Attribute of the parsed namespace holding the names of the arguments given on the command line.
GIVEN_ATTR = "_launcher_given"


class _Value(argparse.Action):
    """Store a value and remember that the argument was given."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: Optional[str] = None) -> None:
        setattr(namespace, self.dest, values)
        _mark_given(namespace, self.dest)


class _Flag(argparse.Action):
    """A ``store_true`` flag that remembers that it was given."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any):
        super().__init__(option_strings, dest, nargs=0, default=False, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: Optional[str] = None) -> None:
        setattr(namespace, self.dest, True)
        _mark_given(namespace, self.dest)


def _mark_given(namespace: argparse.Namespace, dest: str) -> None:
    given = set(getattr(namespace, GIVEN_ATTR, ()))
    setattr(namespace, GIVEN_ATTR, given | {dest})


def add_env_launcher_args_to_parser(parser: argparse.ArgumentParser, *, require_gym_config: bool = False) -> None:
    """Add the env launcher arguments to ``parser`` (in place).

    Arguments (defaults): ``--num_envs`` (1), ``--device`` ("cpu"), ``--headless``,
    ``--renderer`` (auto | hybrid | fast-rt | rt; "auto"), ``--gym_config`` (""),
    ``--max_episodes`` (None: run until interrupted), ``--preview``,
    ``--filter_visual_rand``, ``--filter_dataset_saving``, ``--seed`` (None). The parsed
    namespace remembers which were given: :func:`launcher_overrides` returns only those,
    so a gym config is overridden only by values given on the command line.

    Args:
        parser: the script's parser.
        require_gym_config: make ``--gym_config`` required (as ``run-env`` does).
    """
    add = parser.add_argument
    add("--num_envs", action=_Value, type=int, default=1, help="number of parallel environments")
    add("--device", action=_Value, default="cpu", help="simulation device (sim_cfg.sim_device)")
    add("--headless", action=_Flag, help="run without a viewer window")
    add("--renderer", action=_Value, default="auto", choices=RENDERERS, help="render_cfg.renderer")
    add("--gym_config", action=_Value, default="", required=require_gym_config,
        help="JSON/YAML gym config file")
    add("--max_episodes", action=_Value, type=int, default=None,
        help="stop after this many episodes (default: run until interrupted)")
    add("--preview", action=_Flag, help="interactive preview; records no dataset")
    add("--filter_visual_rand", action=_Flag, help="drop visual randomization events")
    add("--filter_dataset_saving", action=_Flag, help="record no dataset")
    add("--seed", action=_Value, type=int, default=None, help="RNG seed")


def launcher_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The given launcher values as flat gym-config overrides (for ``load_gym_config``).

    Keys (only those given): ``num_envs``, ``headless``, ``device``, ``renderer``,
    ``max_episodes``, ``seed``, ``filter_visual_rand``, ``filter_dataset_saving``
    (``--preview`` forces it).
    """
    given = getattr(args, GIVEN_ATTR, set())
    keys = ("num_envs", "headless", "device", "renderer", "max_episodes", "seed", "filter_visual_rand",
            "filter_dataset_saving")
    values = {key: getattr(args, key) for key in keys if key in given}
    if "preview" in given:
        values["filter_dataset_saving"] = True
    return values


def episode_loop(args: argparse.Namespace) -> Iterator[int]:
    """Episode indices: ``range(args.max_episodes)`` when given, else forever (``while True``)."""
    limit = getattr(args, "max_episodes", None)
    return iter(itertools.count()) if limit is None else iter(range(int(limit)))
