"""Validate the functor template's names before cookiecutter writes anything."""

import sys

try:
    from embodichain_core.templates.names import validate_functor_context
except ImportError:  # pragma: no cover - the template ships with embodichain-core
    sys.exit("ERROR: the functor template needs embodichain-core (pip install embodichain-core)")

CONTEXT = {
    "functor_name": {{ cookiecutter.functor_name | tojson }},
    "kind": {{ cookiecutter.kind | tojson }},
    "distribution_name": {{ cookiecutter.distribution_name | tojson }},
    "package_name": {{ cookiecutter.package_name | tojson }},
}

ERRORS = validate_functor_context(CONTEXT)
if ERRORS:
    for error in ERRORS:
        print(f"ERROR: {error}", file=sys.stderr)
    sys.exit(1)
