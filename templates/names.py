"""Naming rules of the templates: derive every name from one, and validate them.

Shared by ``embodichain new`` (which checks before cookiecutter runs) and the templates'
``pre_gen_project`` hooks (which check whatever the user typed at the prompts). The
derivations mirror the Jinja defaults in each ``cookiecutter.json``.

Example:
    >>> task_context("push_cube")["task_id"]
    'PushCube-v0'
    >>> validate_task_context(task_context("my-task!"))[0]  # doctest: +ELLIPSIS
    "invalid task name 'my-task!': ..."
"""

from __future__ import annotations

import keyword
import re
from typing import Any

#: A task name: words of letters and digits joined by ``-`` or ``_``, starting with a letter.
TASK_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9]*(?:[-_][A-Za-z0-9]+)*$")
#: A functor name: a lowercase Python identifier (what configs write as ``func``).
FUNCTOR_NAME_RE = re.compile(r"^[a-z][a-z0-9]*(?:_[a-z0-9]+)*$")
#: A distribution name (PEP 508), e.g. ``embodichain-push-cube``.
DISTRIBUTION_RE = re.compile(r"^[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?$")
#: A lowercase importable package name.
PACKAGE_RE = re.compile(r"^[a-z_][a-z0-9_]*$")
#: A gymnasium id with a version, ``Name-vN``, without a namespace: the namespace is always
#: the distribution that provides the task (``<distribution>/Name-vN``, added when it registers).
TASK_ID_RE = re.compile(r"^[A-Za-z][\w.:-]*-v\d+$")
#: The functor template's kinds.
FUNCTOR_KINDS = ("observation", "reward", "event", "randomization")
#: The functor template's default one-line description of each kind: what the baked example
#: functor of that kind does. Mirrors the ``description`` default of ``functor/cookiecutter.json``.
FUNCTOR_DESCRIPTIONS = {
    "observation": "Position of an object",
    "reward": "Minus the distance from an object to a target point",
    "event": "Shift an object by a random offset",
    "randomization": "Randomize the mass of an object",
}
#: Name prefix of randomization functors (``filter_visual_rand`` relies on it).
RANDOMIZE_PREFIX = "randomize_"

TASK_NAME_RULE = "use letters and digits, words joined by '-' or '_', starting with a letter (e.g. push_cube)"
FUNCTOR_NAME_RULE = (
    "use a lowercase Python identifier: letters, digits and '_', starting with a letter (e.g. cube_height)"
)


class TemplateNameError(ValueError):
    """One or more names of a template context are invalid (one problem per line)."""


def class_name(name: str) -> str:
    """``push_cube``/``push-cube``/``PushCube`` -> ``PushCube``."""
    return "".join(part[:1].upper() + part[1:] for part in re.split(r"[-_]", name))


def task_context(name: str, **overrides: Any) -> dict[str, Any]:
    """The task template's names derived from ``name``, then ``overrides`` (``None`` skipped)."""
    ctx: dict[str, Any] = {"task_name": name}
    ctx["distribution_name"] = "embodichain-" + name.lower().replace("_", "-")
    ctx["package_name"] = ctx["distribution_name"].replace("-", "_")
    ctx["class_name"] = class_name(name)
    ctx["task_id"] = ctx["class_name"] + "-v0"
    ctx.update({k: v for k, v in overrides.items() if v is not None})
    return ctx


def functor_context(name: str, kind: str | None = None, **overrides: Any) -> dict[str, Any]:
    """The functor template's names derived from ``name`` (``randomize_`` added for that kind).

    With a known ``kind``, the context also has that kind's default ``description``
    (:data:`FUNCTOR_DESCRIPTIONS`).
    """
    if kind == "randomization" and not name.startswith(RANDOMIZE_PREFIX):
        name = RANDOMIZE_PREFIX + name
    ctx: dict[str, Any] = {"functor_name": name}
    if kind is not None:
        ctx["kind"] = kind
    ctx["distribution_name"] = "embodichain-" + name.replace("_", "-")
    ctx["package_name"] = ctx["distribution_name"].replace("-", "_")
    if kind in FUNCTOR_DESCRIPTIONS:
        ctx["description"] = FUNCTOR_DESCRIPTIONS[kind]
    ctx.update({k: v for k, v in overrides.items() if v is not None})
    return ctx


def _package_errors(ctx: dict[str, Any]) -> list[str]:
    errors = []
    dist, package = str(ctx.get("distribution_name", "")), str(ctx.get("package_name", ""))
    if not DISTRIBUTION_RE.match(dist):
        errors.append(f"invalid distribution name {dist!r}: use letters, digits, '-', '_' or '.'")
    if not PACKAGE_RE.match(package) or keyword.iskeyword(package):
        errors.append(f"invalid package name {package!r}: use a lowercase Python identifier")
    return errors


def validate_task_context(ctx: dict[str, Any]) -> list[str]:
    """Problems with the task template's names (empty when all are valid)."""
    name = str(ctx.get("task_name", ""))
    if not TASK_NAME_RE.match(name):
        return [f"invalid task name {name!r}: {TASK_NAME_RULE}"]
    errors = _package_errors(ctx)
    cls = str(ctx.get("class_name", ""))
    if not cls.isidentifier() or keyword.iskeyword(cls) or not cls[:1].isupper():
        errors.append(f"invalid class name {cls!r}: use a CamelCase Python identifier")
    task_id = str(ctx.get("task_id", ""))
    if "/" in task_id:
        bare, dist = task_id.rpartition("/")[2], ctx.get("distribution_name", "the distribution")
        errors.append(
            f"invalid task id {task_id!r}: give it without a namespace ({bare!r}); the gym namespace is always "
            f"the distribution that provides the task, so it is registered as '{dist}/{bare}' and as {bare!r}"
        )
    elif not TASK_ID_RE.match(task_id):
        errors.append(f"invalid task id {task_id!r}: a gymnasium id ending in a version, like 'PushCube-v0' (Name-vN)")
    steps = ctx.get("max_episode_steps", 1)
    if not str(steps).isdigit() or int(steps) < 1:
        errors.append(f"invalid max_episode_steps {steps!r}: use a positive integer")
    return errors


def validate_functor_context(ctx: dict[str, Any]) -> list[str]:
    """Problems with the functor template's names (empty when all are valid)."""
    name, kind = str(ctx.get("functor_name", "")), ctx.get("kind", FUNCTOR_KINDS[0])
    if isinstance(kind, list):  # cookiecutter's choice variable before a choice is made
        kind = kind[0]
    if not FUNCTOR_NAME_RE.match(name) or keyword.iskeyword(name):
        return [f"invalid functor name {name!r}: {FUNCTOR_NAME_RULE}"]
    errors = _package_errors(ctx)
    if kind not in FUNCTOR_KINDS:
        errors.append(f"invalid functor kind {kind!r}: choose one of {', '.join(FUNCTOR_KINDS)}")
    elif kind == "randomization" and not name.startswith(RANDOMIZE_PREFIX):
        errors.append(
            f"invalid functor name {name!r}: randomization functors are named "
            f"{RANDOMIZE_PREFIX}* (e.g. {RANDOMIZE_PREFIX}{name})"
        )
    return errors


def check(errors: list[str]) -> None:
    """Raise :class:`TemplateNameError` listing ``errors``, if any."""
    if errors:
        raise TemplateNameError("\n".join(errors))
