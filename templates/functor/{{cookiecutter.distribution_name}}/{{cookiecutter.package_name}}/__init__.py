"""{{ cookiecutter.distribution_name }}: the embodichain {{ cookiecutter.kind }} functor ``{{ cookiecutter.functor_name }}``."""

__version__ = "{{ cookiecutter.version }}"
