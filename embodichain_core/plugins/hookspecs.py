"""Hook specifications of the embodichain plugin host.

Every hook receives a typed ``register`` object and returns nothing (the style of
tox 4 and ``llm``): the register object records *who* registered *what*: every
entry is owned by its plugin and keeps the qualified name ``<plugin>:<name>``, so two
plugins may use the same name without disabling each other. Implement hooks with :data:`hookimpl`:

Example:
    >>> from embodichain_core.plugins import hookimpl
    >>> @hookimpl
    ... def embodichain_register_functors(register):
    ...     register("randomize_light", "my_pkg.events:randomize_light",
    ...              kind="event", category="randomization.visual")

Targets given as ``"module:attr"`` strings are imported on first use, which keeps
``import embodichain_core`` (and plugin loading) cheap.

This module also defines the register objects the hooks receive
(:class:`FunctorRegister`, :class:`RobotRegister`, :class:`SolverRegister`,
:class:`SensorRegister`, :class:`AssetRegister`, :class:`TaskRegister`, :class:`CommandRegister`).
"""

from __future__ import annotations

from typing import Any, Callable

import pluggy

from embodichain_core.plugins.registry import (
    Entry,
    Registry,
    check_target_string,
    is_lazy_target,
)
from embodichain_core.utils.suggest import did_you_mean

PROJECT_NAME = "embodichain"

hookspec = pluggy.HookspecMarker(PROJECT_NAME)
hookimpl = pluggy.HookimplMarker(PROJECT_NAME)


# --- typed register objects handed to the hooks ---------------------------------------

FUNCTOR_KINDS = ("event", "observation", "reward", "action", "dataset")
#: Functor category removed by ``filter_visual_rand`` (with names ``randomize_*``).
VISUAL_RANDOMIZATION = "randomization.visual"


class BaseRegister:
    """Registers into ``registry`` on behalf of the plugin ``provider``.

    Args:
        registry: the registry to fill.
        provider: plugin name recorded on every entry.
        on_add: called with each new entry (the plugin manager records them, so a
            failing plugin's registrations can be rolled back).
    """

    def __init__(self, registry: Registry, provider: str, on_add: Callable[[Entry], None] | None = None):
        self.registry = registry
        self.provider = provider
        self._on_add = on_add

    def _add(self, name: str, target: Any, meta: dict[str, Any] | None = None, *, lazy: bool | None = None) -> Entry:
        before = self.registry.find_own(self.provider, name)
        entry = self.registry.add(name, target, self.provider, meta, lazy=lazy)
        if entry is not before and self._on_add is not None:
            self._on_add(entry)
        return entry

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.registry.kind} for {self.provider!r}>"


class FunctorRegister(BaseRegister):
    """``register(name, target, *, kind, category="", description="")``."""

    def __call__(self, name: str, target: Any, *, kind: str, category: str = "", description: str = "") -> Entry:
        """Register a functor.

        Args:
            name: the name configs use (``func: "randomize_light"``).
            target: callable/class or ``"module:attr"``.
            kind: one of ``event``, ``observation``, ``reward``, ``action``, ``dataset``.
            category: free text such as ``"randomization.visual"``.
            description: one line; defaults to the target's first docstring line.
        """
        if kind not in FUNCTOR_KINDS:
            raise ValueError(
                f"functor {name!r} from {self.provider!r}: unknown kind {kind!r}." + did_you_mean(kind, FUNCTOR_KINDS)
            )
        meta = {"kind": kind, "category": category, "description": description}
        return self._add(name, target, meta)


class RobotRegister(BaseRegister):
    """``register(name, cfg_class)``: lookups ignore case and a trailing ``Cfg``."""

    def __call__(self, name: str, cfg_class: Any) -> Entry:
        """Register a robot config class (or ``"module:Class"``) as ``name``."""
        return self._add(name, cfg_class)


class SolverRegister(BaseRegister):
    """``register(name, solver_class, description="")``: kinematics solvers for ``solver_cfg``.

    Lookups ignore case and a trailing ``Cfg``. The solver class must offer
    ``from_config(cfg, robot, part) -> solver`` (see :func:`embodichain_register_solvers`).
    """

    def __call__(self, name: str, solver_class: Any, description: str = "") -> Entry:
        """Register a solver class (or ``"module:Class"``) as ``name`` (a ``class_type``)."""
        return self._add(name, solver_class, {"description": description})


class SensorRegister(BaseRegister):
    """``register(sensor_type, cfg_class, sensor_class)``."""

    def __call__(self, sensor_type: str, cfg_class: Any, sensor_class: Any) -> Entry:
        """Register a sensor; the entry's target is the config class.

        ``entry.resolve_meta("sensor_class")`` gives the sensor class.
        """
        if is_lazy_target(sensor_class):
            check_target_string(sensor_class, f"sensor {sensor_type!r} from {self.provider!r}")
        return self._add(sensor_type, cfg_class, {"sensor_class": sensor_class})


class AssetRegister(BaseRegister):
    """``register(name, root)``: a data root directory or a zero-arg callable."""

    def __call__(self, name: str, root: Any) -> Entry:
        """Register a data root (``str``/``os.PathLike``, or a callable returning one)."""
        import os

        if not (isinstance(root, (str, os.PathLike)) or callable(root)):
            raise TypeError(
                f"asset root {name!r} from {self.provider!r} must be a path or a callable, got {type(root).__name__}"
            )
        return self._add(name, root, lazy=False)


class TaskRegister(BaseRegister):
    """``register(task_id, entry_point, *, max_episode_steps=None, kwargs=None, ...)``."""

    def __call__(
        self,
        task_id: str,
        entry_point: str,
        *,
        max_episode_steps: int | None = None,
        kwargs: dict[str, Any] | None = None,
        config: Any = None,
        description: str = "",
    ) -> Entry:
        """Register a task and its gymnasium id.

        Args:
            task_id: gym id such as ``"PushCube-v1"``.
            entry_point: ``"module:Class"``; imported by ``gymnasium.make``.
            max_episode_steps: episode limit, passed to the env as a kwarg.
            kwargs: default constructor kwargs.
            config: default config (path or mapping), kept in ``entry.meta``.
            description: one line shown by ``embodichain list tasks``.
        """
        if not is_lazy_target(entry_point):
            raise ValueError(
                f"task {task_id!r} from {self.provider!r}: entry_point must be a "
                f"'module:Class' string, got {entry_point!r}"
            )
        gym_kwargs = dict(kwargs or {})
        if max_episode_steps is not None:
            gym_kwargs["_registered_max_episode_steps"] = max_episode_steps
        meta = {
            "max_episode_steps": max_episode_steps,
            "kwargs": gym_kwargs,
            "config": config,
            "description": description,
        }
        return self._add(task_id, entry_point, meta)


class CommandRegister(BaseRegister):
    """``register(name, target, help="")``: ``target(argv: list[str]) -> int``."""

    def __call__(self, name: str, target: Any, help: str = "") -> Entry:  # noqa: A002
        """Register a CLI subcommand (``"module:function"`` keeps ``--help`` fast)."""
        return self._add(name, target, {"help": help})


REGISTER_CLASSES: dict[str, type[BaseRegister]] = {
    "functors": FunctorRegister,
    "robots": RobotRegister,
    "solvers": SolverRegister,
    "sensors": SensorRegister,
    "assets": AssetRegister,
    "tasks": TaskRegister,
    "commands": CommandRegister,
}


# --- hook specifications ----------------------------------------------------------------


@hookspec
def embodichain_register_functors(register: FunctorRegister) -> None:
    """Register manager functors (events, observations, rewards, actions, datasets).

    Args:
        register: ``register(name, target, *, kind, category="", description="")``.
            ``target`` is a callable/class or a lazy ``"module:attr"`` string;
            ``kind`` is one of ``event``, ``observation``, ``reward``, ``action``,
            ``dataset``; ``category`` is free text such as
            ``"randomization.visual"`` (``filter_visual_rand`` drops functors of
            that category whose name starts with ``randomize_``).

    Example:
        >>> @hookimpl
        ... def embodichain_register_functors(register):
        ...     register("randomize_light", "my_pkg.events:randomize_light",
        ...              kind="event", category="randomization.visual")
        ...     register("joint_pos", "my_pkg.obs:joint_pos", kind="observation")
    """


@hookspec
def embodichain_register_robots(register: RobotRegister) -> None:
    """Register robot config classes, looked up by ``class_type``/``robot_type``.

    Args:
        register: ``register(name, cfg_class)``; ``cfg_class`` is a class or a
            lazy ``"module:Class"`` string. Lookups ignore case and accept the
            name with a trailing ``Cfg``.

    Example:
        >>> @hookimpl
        ... def embodichain_register_robots(register):
        ...     register("DexforceW1", "embodichain_robots.w1:DexforceW1Cfg")
    """


@hookspec
def embodichain_register_solvers(register: SolverRegister) -> None:
    """Register kinematics solver classes, named by ``solver_cfg.<part>.class_type``.

    A robot section's ``"solver_cfg": {part: {"class_type": name, ...}}`` builds one
    solver per control part through the class registered as ``name``; the core holds
    no solver code. The class must provide
    ``from_config(cfg: dict, robot: Robot, part: str) -> solver``: ``cfg`` is the part's
    mapping (``class_type`` included), ``robot`` the built robot; a bad value raises
    ``ConfigError`` with its key relative to the part (``"end_link_name"``), which the
    core reports as ``robot.solver_cfg.<part>.end_link_name``. The solver it returns
    has ``joint_ids``, ``root_link_name``, ``get_fk`` and ``get_ik`` (see
    :mod:`embodichain_core.sim.entities.robot`).

    Args:
        register: ``register(name, solver_class, description="")``; ``solver_class`` is
            a class or a lazy ``"module:Class"`` string. Lookups ignore case and a
            trailing ``Cfg``; ``<plugin>:<name>`` picks one plugin's solver.

    Example:
        >>> @hookimpl
        ... def embodichain_register_solvers(register):
        ...     register("DLSSolver", "my_pkg.ik:DLSSolver")
    """


@hookspec
def embodichain_register_sensors(register: SensorRegister) -> None:
    """Register sensors by their ``sensor_type``.

    Args:
        register: ``register(sensor_type, cfg_class, sensor_class)``; both classes
            may be lazy ``"module:Class"`` strings.

    Example:
        >>> @hookimpl
        ... def embodichain_register_sensors(register):
        ...     register("StereoCamera", "my_pkg.stereo:StereoCameraCfg",
        ...              "my_pkg.stereo:StereoCamera")
    """


@hookspec
def embodichain_register_assets(register: AssetRegister) -> None:
    """Register data roots searched by ``get_data_path``.

    Args:
        register: ``register(name, root)``; ``root`` is a directory path or a
            zero-argument callable returning one (called on first use, e.g. to
            download or locate data lazily).

    Example:
        >>> @hookimpl
        ... def embodichain_register_assets(register):
        ...     register("embodichain-assets", Path(__file__).parent / "data")
    """


@hookspec
def embodichain_register_tasks(register: TaskRegister) -> None:
    """Register gym tasks; each is also registered with gymnasium.

    Args:
        register: ``register(task_id, entry_point, *, max_episode_steps=None,
            kwargs=None, config=None, description="")``. ``entry_point`` is a
            ``"module:Class"`` string, imported only by ``gymnasium.make``. The
            episode limit lives inside the env: it is passed as the
            ``max_episode_steps`` kwarg, never as gymnasium's ``TimeLimit``.

    Example:
        >>> @hookimpl
        ... def embodichain_register_tasks(register):
        ...     register("PushCube-v1", "my_pkg.push:PushCubeEnv",
        ...              max_episode_steps=200, description="Push a cube")
    """


@hookspec
def embodichain_register_commands(register: CommandRegister) -> None:
    """Register ``embodichain`` CLI subcommands.

    Args:
        register: ``register(name, target, help="")``; ``target`` is a
            ``"module:function"`` string (or a function) taking
            ``argv: list[str]`` and returning an exit code. It is imported only
            when the command runs, so ``embodichain --help`` stays fast.

    Example:
        >>> @hookimpl
        ... def embodichain_register_commands(register):
        ...     register("dataset", "my_pkg.cli:main", help="Inspect datasets")
    """


#: Hook name of every registry kind, in the order the hooks are called.
REGISTER_HOOKS: dict[str, str] = {
    "commands": "embodichain_register_commands",
    "assets": "embodichain_register_assets",
    "robots": "embodichain_register_robots",
    "solvers": "embodichain_register_solvers",
    "sensors": "embodichain_register_sensors",
    "functors": "embodichain_register_functors",
    "tasks": "embodichain_register_tasks",
}
