"""Validate the task template's names before cookiecutter writes anything."""

import sys

try:
    from embodichain_core.templates.names import validate_task_context
except ImportError:  # pragma: no cover - the template ships with embodichain-core
    sys.exit("ERROR: the task template needs embodichain-core (pip install embodichain-core)")

CONTEXT = {
    "task_name": {{ cookiecutter.task_name | tojson }},
    "distribution_name": {{ cookiecutter.distribution_name | tojson }},
    "package_name": {{ cookiecutter.package_name | tojson }},
    "class_name": {{ cookiecutter.class_name | tojson }},
    "task_id": {{ cookiecutter.task_id | tojson }},
    "max_episode_steps": {{ cookiecutter.max_episode_steps | string | tojson }},
}

ERRORS = validate_task_context(CONTEXT)
if ERRORS:
    for error in ERRORS:
        print(f"ERROR: {error}", file=sys.stderr)
    sys.exit(1)
