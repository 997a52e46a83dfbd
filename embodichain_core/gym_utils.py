"""Launcher arguments for env scripts (EmbodiChain's ``lab.gym.utils.gym_utils`` surface).

:func:`add_env_launcher_args_to_parser` is the one definition of the env launcher
arguments: a script's parser gets them from it, and so does ``embodichain run-env``
(:func:`embodichain_core.cli.run_env.build_parser`), so both accept the same flags, with
the same defaults (:data:`LAUNCHER_DEFAULTS`, EmbodiChain's) and the same renderer choices
(:data:`RENDERERS`). Unlike EmbodiChain, a CLI value overrides a gym config only when it
is given: the parsed namespace keeps the defaults (``args.num_envs == 1``) and remembers
which arguments were given, and :func:`launcher_overrides` returns only those.

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

__all__ = [
    "add_env_launcher_args_to_parser",
    "launcher_overrides",
    "episode_loop",
    "RENDERERS",
    "LAUNCHER_DEFAULTS",
]

#: Renderer names accepted by ``--renderer`` (EmbodiChain's; all render with MuJoCo here).
RENDERERS = ("auto", "hybrid", "fast-rt", "rt")


#: The value of each launcher argument when it is not given (EmbodiChain's defaults). A
#: default never overrides a gym config: only given values do (:func:`launcher_overrides`).
LAUNCHER_DEFAULTS: dict[str, Any] = {
    "num_envs": 1,
    "device": "cpu",
    "headless": False,
    "renderer": "auto",
    "gym_config": "",
    "max_episodes": None,
    "preview": False,
    "filter_visual_rand": False,
    "filter_dataset_saving": False,
    "seed": None,
    "backend": None,
    "viewer": None,
}

#: Launcher arguments that map onto a gym-config override of the same name.
OVERRIDE_KEYS = (
    "num_envs",
    "headless",
    "device",
    "renderer",
    "max_episodes",
    "seed",
    "filter_visual_rand",
    "filter_dataset_saving",
    "backend",
    "viewer",
)

#: Attribute of the parsed namespace holding the names of the arguments given on the command line.
GIVEN_ATTR = "_launcher_given"


class _Value(argparse.Action):
    """Store a value and remember that the argument was given."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: Optional[str] = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        _mark_given(namespace, self.dest)


class _Flag(argparse.Action):
    """A ``store_true`` flag that remembers that it was given."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any):
        super().__init__(option_strings, dest, nargs=0, default=False, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: Optional[str] = None,
    ) -> None:
        setattr(namespace, self.dest, True)
        _mark_given(namespace, self.dest)


def _mark_given(namespace: argparse.Namespace, dest: str) -> None:
    given = set(getattr(namespace, GIVEN_ATTR, ()))
    setattr(namespace, GIVEN_ATTR, given | {dest})


def _backends() -> tuple[str, ...]:
    from embodichain_core.sim.cfg import BACKENDS  # not at import: importing the sim package configures GL

    return BACKENDS


def _viewer_modes() -> tuple[str, ...]:
    from embodichain_core.viewing import VIEWER_MODES

    return VIEWER_MODES


def add_env_launcher_args_to_parser(parser: argparse.ArgumentParser, *, require_gym_config: bool = False) -> None:
    """Add the env launcher arguments to ``parser`` (in place).

    Arguments (defaults from :data:`LAUNCHER_DEFAULTS`): ``--num_envs`` (1), ``--device``
    ("cpu"), ``--headless``, ``--renderer`` (one of :data:`RENDERERS`; "auto"),
    ``--gym_config`` (""), ``--backend`` (one of ``embodichain_core.sim.cfg.BACKENDS``; None: the config's),
    ``--max_episodes`` (None: run until interrupted), ``--preview``,
    ``--filter_visual_rand``, ``--filter_dataset_saving``, ``--seed`` (None). The parsed
    namespace remembers which were given: :func:`launcher_overrides` returns only those,
    so a gym config is overridden only by values given on the command line.

    Args:
        parser: the script's parser.
        require_gym_config: make ``--gym_config`` required.
    """
    d = LAUNCHER_DEFAULTS
    add = parser.add_argument
    add(
        "--gym_config",
        action=_Value,
        default=d["gym_config"],
        required=require_gym_config,
        metavar="FILE",
        help="JSON/YAML gym config file (EmbodiChain layout)",
    )
    add(
        "--num_envs",
        action=_Value,
        type=int,
        default=d["num_envs"],
        metavar="N",
        help=f"number of parallel environments (default: the config's, else {d['num_envs']})",
    )
    add("--headless", action=_Flag, help="run without a viewer window (default: the config's)")
    add(
        "--viewer",
        action=_Value,
        default=d["viewer"],
        choices=_viewer_modes(),
        help="open a viewer (implies headless false): auto = native window when DISPLAY/WAYLAND_DISPLAY "
        "is set, else a browser page on localhost; none = no viewer (default: the config's, sim_cfg.viewer)",
    )
    add(
        "--device",
        action=_Value,
        default=d["device"],
        metavar="DEVICE",
        help=f"simulation device, sim_cfg.sim_device (default: the config's, else {d['device']})",
    )
    add(
        "--renderer",
        action=_Value,
        default=d["renderer"],
        choices=RENDERERS,
        help=f"render_cfg.renderer (default: the config's, else {d['renderer']})",
    )
    add(
        "--backend",
        action=_Value,
        default=d["backend"],
        choices=_backends(),
        help="simulation backend, sim_cfg.backend: mujoco_batch (CPU threads) or warp (MuJoCo Warp on "
        "--device cpu/cuda) (default: the config's, else mujoco_batch)",
    )
    add(
        "--max_episodes",
        action=_Value,
        type=int,
        default=d["max_episodes"],
        metavar="N",
        help="stop after this many episodes, summed over envs (default: the config's; scripts: run until interrupted)",
    )
    add("--seed", action=_Value, type=int, default=d["seed"], metavar="SEED", help="RNG seed (default: the config's)")
    add(
        "--preview",
        action=_Flag,
        help="preview instead of running, recording no dataset (run-env: build, reset, step once, "
        "describe the spaces, exit)",
    )
    add("--filter_visual_rand", action=_Flag, help="drop visual randomization events")
    add("--filter_dataset_saving", action=_Flag, help="record no dataset")


def launcher_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The given launcher values as flat gym-config overrides (for ``load_gym_config``).

    Args:
        args: a namespace parsed by a parser with :func:`add_env_launcher_args_to_parser`.

    Returns:
        Only the keys given on the command line, among ``num_envs``, ``headless``,
        ``device``, ``renderer``, ``backend``, ``max_episodes``, ``seed``, ``filter_visual_rand``,
        ``filter_dataset_saving`` (``--preview`` forces it to ``True``) and ``viewer``
        (``--viewer`` other than ``none`` sets ``headless`` to ``False``).

    Raises:
        ConfigError: ``--viewer`` (other than ``none``) together with ``--headless``.
    """
    given: set[str] = getattr(args, GIVEN_ATTR, set())
    values = {key: getattr(args, key) for key in OVERRIDE_KEYS if key in given}
    if "preview" in given:
        values["filter_dataset_saving"] = True
    if values.get("viewer") not in (None, "none"):
        if values.get("headless"):
            from embodichain_core.config.errors import ConfigError

            raise ConfigError("viewer", f"--viewer {values['viewer']} opens a viewer: drop --headless (or the flag)")
        values["headless"] = False
    return values


def episode_loop(args: argparse.Namespace) -> Iterator[int]:
    """Episode indices: ``range(args.max_episodes)`` when given, else forever (``while True``)."""
    limit = getattr(args, "max_episodes", None)
    return iter(itertools.count()) if limit is None else iter(range(int(limit)))
