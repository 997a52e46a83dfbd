"""Deterministic mutations of the main job's gym config (PickFork-v1 on the W1), for the
config fuzz test.

Each :class:`Mutation` changes one value (or deletes one key) of the config, by its
path in the gym-config layout (``rigid_object[0].attrs.mass``). ``expect`` says what
a correct build does with it:

* ``"error"``: a ``ConfigError`` whose message names ``names`` (the key path, by
  default the mutated path; for a deleted key its entry and the key);
* ``"ok"``: the env builds. Only values that are valid with a documented meaning
  are ``ok``: another value in range, ``0`` mass (the mass comes from the density),
  friction ``0``, restitution ``1``, intensity ``0``, ``None`` for an optional
  randomization range (that quantity is not randomized), a relative light
  intensity range reaching below zero (added to the configured intensity and
  clamped at 0), ``-1`` episode steps (unlimited), ``startup`` instead of ``reset``
  (randomized once), a disabled (``null``) event, an empty drive mapping (the W1
  config merges drive mappings into its per-joint defaults, so they stay), a declared
  custom event mode.

An ``init_qpos`` of another length than the robot's joints is not in the corpus: the
joint count is known only once the robot is built, where the articulation rejects it
(with a ``ValueError`` naming the uid and ``init_qpos``).
"""

from __future__ import annotations

import copy
import math
import re
from dataclasses import dataclass
from typing import Any, Iterator

NAN, INF = math.nan, math.inf
DELETE = object()


@dataclass(frozen=True)
class Mutation:
    """One change of the base config."""

    path: str
    label: str
    value: Any
    expect: str  # "error" | "ok"
    names: tuple = ()

    @property
    def id(self) -> str:
        return f"{self.path}:{self.label}"

    def must_name(self) -> list[str]:
        """Substrings the error message must contain."""
        if self.names:
            return list(self.names)
        if self.value is DELETE:
            parent, key = split_last(self.path)
            return [parent, key] if parent else [key]
        return [self.path]


_TOKEN = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def parse_path(path: str) -> list[Any]:
    """``"a.b[0].c"`` -> ``["a", "b", 0, "c"]``; a key holding dots or brackets is
    written in parentheses: ``"robot.drive_pros.stiffness.((LEFT|RIGHT)_FINGER[12])"``."""
    keys: list[Any] = []
    while path:
        if path.startswith(".("):
            end = path.index(")", 2)
            while end + 1 < len(path) and path[end + 1] not in ".[":
                end = path.index(")", end + 1)
            keys.append(path[2:end])
            path = path[end + 1 :]
            continue
        match = _TOKEN.match(path.lstrip("."))
        path = path.lstrip(".")[match.end() :]
        keys.append(match.group(1) if match.group(1) is not None else int(match.group(2)))
    return keys


def split_last(path: str) -> tuple[str, str]:
    """``("a.b", "c")`` for ``"a.b.c"``."""
    head, _, tail = path.rpartition(".")
    return head, tail.strip("()")


def apply(data: dict, mutation: Mutation) -> dict:
    """A deep copy of ``data`` with ``mutation`` applied."""
    out = copy.deepcopy(data)
    keys = parse_path(mutation.path)
    node = out
    for key in keys[:-1]:
        node = node[key]
    if mutation.value is DELETE:
        del node[keys[-1]]
    else:
        node[keys[-1]] = copy.deepcopy(mutation.value)
    return out


# -- value classes ------------------------------------------------------------------------------
_WRONG_TYPES = [("str", "x"), ("none", None), ("list", [1.0]), ("dict", {"v": 1}), ("nan", NAN), ("inf", INF)]


def _muts(path: str, errors: list, oks: list = (), names: tuple = ()) -> list[Mutation]:
    return [Mutation(path, label, value, "error", names) for label, value in errors] + [
        Mutation(path, label, value, "ok") for label, value in oks
    ]


def positive(path: str, ok: float, zero_ok: bool = False) -> list[Mutation]:
    zero = [] if zero_ok else [("zero", 0.0)]
    return _muts(path, [*_WRONG_TYPES, ("negative", -1.0), *zero], [("other", ok)] + ([("zero", 0.0)] * zero_ok))


def non_negative(path: str, ok: float) -> list[Mutation]:
    return _muts(path, [*_WRONG_TYPES, ("negative", -0.1)], [("zero", 0.0), ("other", ok)])


def unit(path: str, ok: float) -> list[Mutation]:
    return _muts(path, [("str", "x"), ("nan", NAN), ("negative", -0.1), ("above_one", 1.5)], [("other", ok)])


def vec(path: str, base: list, low: float = None, high: float = None, low_open: bool = False) -> list[Mutation]:
    errors = [
        ("short", base[:-1]),
        ("long", [*base, base[-1]]),
        ("nan", [NAN, *base[1:]]),
        ("inf", [*base[:-1], INF]),
        ("str", "x"),
        ("dict", {"x": 1}),
        ("none", None),
        ("str_item", ["a", *base[1:]]),
    ]
    if low is not None:
        errors.append(("below", [low if low_open else low - 1.0, *base[1:]]))
    if high is not None:
        errors.append(("above", [high + 0.5, *base[1:]]))
    return _muts(path, errors, [("other", [float(v) * 0.9 for v in base])])


def size(path: str, ok: int, huge: int) -> list[Mutation]:
    return _muts(
        path,
        [("zero", 0), ("negative", -1), ("float", 1.5), ("str", "8"), ("none", None), ("huge", huge)],
        [("other", ok)],
    )


def range_pair(path: str, low: Any, high: Any, optional: bool, bounded: tuple = ()) -> list[Mutation]:
    def nan_of(v: Any) -> Any:
        return [NAN, *v[1:]] if isinstance(v, list) else NAN

    errors = [
        ("swapped", [high, low]),
        ("one", [low]),
        ("three", [low, high, high]),
        ("str", "x"),
        ("dict", {"low": low}),
        ("nan", [nan_of(low), high]),
        ("strs", ["a", "b"]),
    ]
    if isinstance(low, list):
        errors.append(("short_bound", [low[:-1], high[:-1]]))
    errors += [(f"bound_{label}", value) for label, value in bounded]
    oks = [("none", None)] if optional else []
    if not optional:
        errors.append(("none", None))
    return _muts(path, errors, oks)


def event_mode(path: str) -> list[Mutation]:
    return _muts(
        path,
        [
            ("typo_rset", "rset"),
            ("typo_intervall", "intervall"),
            ("case", "Reset"),
            ("typo_startp", "startp"),
            ("int", 3),
            ("none", None),
            ("empty", ""),
        ],
        [("startup", "startup")],
    )


def delete(path: str, names: tuple = ()) -> list[Mutation]:
    return [Mutation(path, "delete", DELETE, "error", names)]


def single(path: str, label: str, value: Any, expect: str = "error", names: tuple = ()) -> list[Mutation]:
    return [Mutation(path, label, value, expect, names)]


# -- the corpus ---------------------------------------------------------------------------------
_EV = "env.events"
_FINGERS = "((LEFT|RIGHT)_FINGER[12])"


def run_and_sim() -> Iterator[Mutation]:
    yield from size("num_envs", 3, 10**7)
    yield from _muts(
        "max_episode_steps", [("str", "300"), ("float", 1.5), ("huge", 10**10), ("none", None)], [("unlimited", -1)]
    )
    yield from _muts("max_episodes", [("zero", 0), ("str", "x")])
    yield from _muts(
        "physics_dt",
        [("zero", 0.0), ("negative", -0.01), ("nan", NAN), ("inf", INF), ("str", "fast"), ("huge", 10.0)],
        [("other", 0.005)],
    )
    yield from _muts("physics_substeps", [("zero", 0), ("huge", 10**6), ("float", 2.5)], [("other", 2)])
    yield from single("physics_config.cone", "typo", "eliptic")
    yield from _muts("physics_config.iterations", [("zero", 0), ("negative", -5)], [("other", 100)])
    yield from vec("physics_config.gravity", [0.0, 0.0, -9.81])
    yield from single("headless", "str", "yes")
    yield from single("device", "int", 3)
    yield from single("env.control_parts", "str", "right_arm")
    yield from single("env.control_parts", "unknown_part", ["right_arm", "no_such_part"], names=("control_parts",))
    yield from _muts(
        "env.custom_event_modes",
        [("str", "attach"), ("int_item", [3]), ("builtin", ["reset"])],
        [("declared", ["attach"])],
    )
    yield from single("env.sim_steps_per_control", "huge", 10**7)
    yield from single("env.seed", "str", "zero")


def events() -> Iterator[Mutation]:
    for name in ("replace_fork", "fork_mass", "fork_pose", "light", "table_material"):
        yield from delete(f"{_EV}.{name}.params.entity_cfg")
        yield from single(f"{_EV}.{name}.params.entity_cfg.uid", "unknown_uid", "forkk")
        yield from single(f"{_EV}.{name}.params.entity_cfg", "str", "fork")
        yield from delete(f"{_EV}.{name}.func")
    for name in ("fork_mass", "light", "grip_contacts"):
        yield from event_mode(f"{_EV}.{name}.mode")
    yield from single(f"{_EV}.fork_mass.func", "typo", "randomize_rigid_object_mas")
    yield from single(f"{_EV}.fork_mass.interval_step", "zero", 0)
    yield from single(f"{_EV}.fork_mass.is_global", "str", "yes")
    yield from single(f"{_EV}.fork_mass.params.mas_range", "unknown_param", [0.03, 0.1])
    yield from single(f"{_EV}.fork_mass", "disabled", None, "ok")
    yield from single(f"{_EV}.fork_mass", "str", "x")
    yield from single(f"{_EV}.fork_mass.params.relative", "str", "yes")
    yield from range_pair(
        f"{_EV}.fork_mass.params.mass_range",
        0.03,
        0.1,
        optional=False,
        bounded=[("zero", [0.0, 0.1]), ("negative", [-0.1, 0.1]), ("inf", [0.03, INF])],
    )
    low, high = [-0.04, -0.05, 0.0], [0.04, 0.05, 0.0]
    yield from range_pair(f"{_EV}.fork_pose.params.position_range", low, high, optional=True)
    yield from range_pair(f"{_EV}.fork_pose.params.rotation_range", [0.0, 0.0, -30.0], [0.0, 0.0, 30.0], True)
    yield from single(f"{_EV}.fork_pose.params.relative_rotation", "str", "true")
    grey, white = [0.7, 0.7, 0.7], [1.0, 1.0, 1.0]
    yield from range_pair(
        f"{_EV}.light.params.color_range",
        grey,
        white,
        optional=True,
        bounded=[("above_one", [grey, [1.5, 1.0, 1.0]]), ("negative", [[-0.1, 0.7, 0.7], white])],
    )
    yield from range_pair(f"{_EV}.light.params.intensity_range", 15.0, 30.0, optional=True)
    yield from single(f"{_EV}.light.params.intensity_range", "relative_negative", [-5.0, 10.0], "ok")
    yield from unit(f"{_EV}.table_material.params.random_texture_prob", 1.0)
    yield from range_pair(
        f"{_EV}.table_material.params.base_color_range",
        [0.2] * 3,
        [1.0] * 3,
        optional=True,
        bounded=[("above_one", [[0.2] * 3, [1.2, 1.0, 1.0]])],
    )
    yield from single(f"{_EV}.table_material.params.texture_path", "int", 3)
    yield from single(f"{_EV}.table_material.params.texture_path", "missing", "NoSuchTextures/none")
    yield from delete(f"{_EV}.replace_fork.params.folder_path")
    yield from single(f"{_EV}.replace_fork.params.folder_path", "int", 3)
    yield from single(f"{_EV}.replace_fork.params.folder_path", "missing", "NoSuchFolder/forks/")
    yield from single(f"{_EV}.grip_contacts.params.impratio", "nan", NAN)
    yield from single("env.events", "list", [])


def observations_and_dataset() -> Iterator[Mutation]:
    obs = "env.observations.fork_pose"
    yield from delete(f"{obs}.mode", names=(obs, "mode 'modify'"))
    yield from delete(f"{obs}.name")
    yield from delete(f"{obs}.params.entity_cfg")
    yield from _muts(f"{obs}.mode", [("typo", "ad"), ("none", None)])
    yield from single(f"{obs}.mode", "modify_missing", "modify", names=(obs, "mode 'modify'"))
    yield from _muts(f"{obs}.name", [("empty", ""), ("empty_level", "a//b"), ("int", 3)])
    yield from single(f"{obs}.params.to_matrix", "str", "yes")
    rec = "env.dataset.lerobot"
    yield from single(f"{rec}.mode", "typo", "sav")
    yield from delete(f"{rec}.func")
    yield from single(f"{rec}.save_failed_episodes", "str", "yes")


def robot() -> Iterator[Mutation]:
    yield from vec("robot.init_pos", [0.0, 0.0, 0.0])
    yield from _muts("robot.init_rot", [("four", [0.0, 0.0, 0.0, 1.0]), ("nan", [0.0, NAN, 0.0])])
    yield from _muts("robot.init_qpos", [("nan_item", [NAN] + [0.0] * 23), ("str", "x")])
    drive, key = "robot.drive_pros", _FINGERS[1:-1]
    yield from _muts(
        f"{drive}.stiffness.{_FINGERS}",
        [("negative", -3000.0), ("nan", NAN), ("str", "stiff")],
        names=(f"{drive}.stiffness.{key}",),
    )
    yield from _muts(
        f"{drive}.damping.{_FINGERS}", [("negative", -100.0), ("inf", INF)], names=(f"{drive}.damping.{key}",)
    )
    yield from _muts(f"{drive}.max_effort.{_FINGERS}", [("negative", -40.0)], names=(f"{drive}.max_effort.{key}",))
    # the W1 config merges a drive mapping into its per-joint defaults: {} keeps them
    yield from single(f"{drive}.stiffness", "empty_mapping", {}, "ok")
    yield from single("robot.class_type", "typo", "DexforceW2")
    yield from single("robot.body_scale", "zero", [1.0, 1.0, 0.0])
    yield from single("robot.uid", "int", 3)
    yield from single("robot.init_poss", "unknown_key", [0.0, 0.0, 0.0])


def sensors_and_lights() -> Iterator[Mutation]:
    cam = "sensor[0]"
    yield from size(f"{cam}.width", 160, 10**6)
    yield from single(f"{cam}.height", "huge", 10**6)
    intr = [150.0, 150.0, 160.0, 90.0]
    yield from _muts(
        f"{cam}.intrinsics", [("short", intr[:3]), ("zero_fx", [0.0, *intr[1:]]), ("nan", [NAN, *intr[1:]])]
    )
    yield from single(f"{cam}.intrinsics_right", "short", intr[:2])
    yield from _muts(f"{cam}.left_to_right_pos", [("short", [0.06, 0.0]), ("nan", [NAN, 0.0, 0.0])])
    # the mount is resolved when the sensor is built: the error names the sensor's uid and the key
    yield from single(f"{cam}.extrinsics.parent", "unknown_body", "eyez", names=("eye_in_head", "extrinsics.parent"))
    yield from _muts(f"{cam}.extrinsics.quat", [("zero", [0.0, 0.0, 0.0, 0.0]), ("short", [1.0, 0.0, 0.0])])
    yield from single(f"{cam}.sensor_type", "typo", "StereoCamra")
    yield from delete(f"{cam}.sensor_type", names=(cam,))
    yield from single(f"{cam}.near", "negative", -1.0)
    yield from single(f"{cam}.enable_depth", "str", "yes")
    lamp = "light.direct[0]"
    yield from non_negative(f"{lamp}.intensity", 10.0)
    yield from vec(f"{lamp}.color", [1.0, 1.0, 1.0], low=0.0, high=1.0)
    yield from single(f"{lamp}.init_pos", "short", [0.0, 0.0])
    yield from single(f"{lamp}.light_type", "typo", "pont")
    yield from single(f"{lamp}.radius", "negative", -1.0)


def objects() -> Iterator[Mutation]:
    table, fork = "background[0]", "rigid_object[0]"
    yield from positive(f"{table}.attrs.mass", 20.0, zero_ok=True)
    yield from non_negative(f"{table}.attrs.static_friction", 0.5)
    yield from single(f"{table}.attrs.dynamic_friction", "negative", -1.0)
    yield from unit(f"{table}.attrs.restitution", 1.0)
    yield from _muts(f"{table}.init_rot", [("short", [0.0, 90.0]), ("nan", [0.0, NAN, 0.0])])
    yield from _muts(f"{table}.body_type", [("dynamic", "dynamic"), ("typo", "statik")])
    yield from delete(f"{table}.shape.fpath")
    yield from single(f"{table}.shape.fpath", "missing", "Nope/missing.ply")
    yield from single(f"{table}.shape.shape_type", "typo", "Meshh")
    yield from single(f"{table}.shape.compute_uv", "str", "yes")
    yield from positive(f"{fork}.attrs.mass", 0.08, zero_ok=True)
    yield from _muts(f"{fork}.attrs.static_friction", [("negative", -1.0), ("inf", INF)])
    yield from single(f"{fork}.attrs.min_position_iters", "zero", 0)
    yield from vec(f"{fork}.body_scale", [0.75, 0.75, 1.0], low=0.0, low_open=True)
    yield from vec(f"{fork}.init_pos", [0.5, -0.2, 0.8225])
    yield from single(f"{fork}.max_convex_hull_num", "zero", 0)
    yield from single(
        f"{fork}.shape.visual_material",
        "rgb_only",
        {"base_color": [1.0, 0.0, 0.0]},
        names=(f"{fork}.shape.visual_material.base_color",),
    )
    yield from single(f"{fork}.mass", "unknown_key", 1.0)
    yield from _muts("rigid_object", [("str", "fork"), ("dict", {}), ("none", None)])
    yield from single("sensor", "dict", {})
    yield from single("light", "list", [])


def implausible() -> Iterator[Mutation]:
    """Valid numbers at nonsense physical scales, undeclared modes and shadowing names."""
    table, fork = "background[0]", "rigid_object[0]"
    yield from single(f"{fork}.init_pos", "huge", [1.0e6, -0.2, 0.8225], names=(f"{fork}.init_pos[0]",))
    yield from single(f"{table}.init_pos", "huge", [0.8, -2.0e6, 0.8], names=(f"{table}.init_pos[1]",))
    yield from single("robot.init_pos", "huge", [0.0, 0.0, 1.0e6], names=("robot.init_pos[2]",))
    yield from single(f"{fork}.attrs.mass", "huge", 1.0e6)
    yield from single(f"{table}.attrs.mass", "huge", 1.0e9)
    yield from single(f"{fork}.attrs.static_friction", "huge", 1.0e6)
    yield from single(f"{table}.attrs.dynamic_friction", "huge", 1.0e9)
    # an unusual scene raises a bound explicitly
    yield from single("physical_limits", "raised", {"position": 5000.0, "mass": 1.0e5}, "ok")
    yield from single("physical_limits", "unknown_quantity", {"speed": 3.0}, names=("physical_limits.speed",))
    yield from single("sensor[0].intrinsics", "negative_cx", [150.0, 150.0, -160.0, 90.0])
    pose = f"{_EV}.fork_pose.params.position_range"
    yield from single(pose, "huge_bound", [[-1.0e9, -0.05, 0.0], [0.04, 0.05, 0.0]])
    yield from single(f"{_EV}.light.params.intensity_range", "huge_bound", [15.0, 1.0e12])
    yield from single(f"{_EV}.fork_mass.mode", "undeclared", "sometimes")
    yield from single(f"{_EV}.light.mode", "undeclared_caps", "EVERY_STEP", names=(f"{_EV}.light.mode",))
    yield from single("env.observations.fork_pose.name", "group", "robot")
    yield from single("env.observations.fork_pose.name", "sensor_group", "sensor")


def mutations() -> list[Mutation]:
    """Every mutation of the corpus, in a fixed order."""
    out: list[Mutation] = []
    for group in (run_and_sim, events, observations_and_dataset, robot, sensors_and_lights, objects, implausible):
        out += list(group())
    return out
