"""The cookiecutter templates of ``embodichain new``, shipped as ``embodichain_core.templates``.

The source lives at the repository root (``templates/``); ``pyproject.toml`` maps it onto
the package ``embodichain_core.templates`` (``[tool.setuptools.package-dir]``) and ships
every file below it as package data, so wheels and editable installs both carry the
templates. :mod:`embodichain_core.templates.names` holds the naming rules shared by the
``embodichain new`` command and the templates' ``pre_gen_project`` hooks.

Example:
    >>> from embodichain_core.templates import template_dir
    >>> (template_dir("task") / "cookiecutter.json").is_file()
    True
"""

from __future__ import annotations

from pathlib import Path

#: Template names, each a cookiecutter template directory next to this file.
TEMPLATES = ("task", "functor")


def template_dir(name: str) -> Path:
    """The directory of the cookiecutter template ``name`` (``"task"`` or ``"functor"``).

    Raises:
        ValueError: ``name`` is not a shipped template.
        FileNotFoundError: the installation lacks the template's files.
    """
    if name not in TEMPLATES:
        raise ValueError(f"unknown template {name!r}; choose one of {', '.join(TEMPLATES)}")
    path = Path(__file__).resolve().parent / name
    if not (path / "cookiecutter.json").is_file():
        raise FileNotFoundError(f"template {name!r} is missing from this installation ({path})")
    return path
