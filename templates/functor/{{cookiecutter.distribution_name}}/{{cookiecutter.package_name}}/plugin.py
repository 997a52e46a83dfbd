"""Registrations of {{ cookiecutter.distribution_name }} (its ``embodichain`` entry point).

The functor is registered as a lazy ``"module:attr"`` string: it is imported when an env
config first uses it (``func: "{{ cookiecutter.functor_name }}"``), not when plugins load.
"""

from __future__ import annotations

from embodichain_core.plugins import FunctorRegister, hookimpl

FUNCTOR_NAME = "{{ cookiecutter.functor_name }}"
{%- if cookiecutter.kind == "randomization" %}
#: Randomization functors are event functors named ``randomize_*``. With the category
#: ``"randomization.visual"`` instead, ``filter_visual_rand`` would drop this one.
KIND, CATEGORY = "event", "randomization.physics"
{%- elif cookiecutter.kind == "event" %}
KIND, CATEGORY = "event", "spatial"
{%- else %}
KIND, CATEGORY = "{{ cookiecutter.kind }}", ""
{%- endif %}


@hookimpl
def embodichain_register_functors(register: FunctorRegister) -> None:
    """Register ``{{ cookiecutter.functor_name }}``."""
    register(FUNCTOR_NAME, "{{ cookiecutter.package_name }}.functors:{{ cookiecutter.functor_name }}", kind=KIND,
             category=CATEGORY, description="{{ cookiecutter.description }}")
