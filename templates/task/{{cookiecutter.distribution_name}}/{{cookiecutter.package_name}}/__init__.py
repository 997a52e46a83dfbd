"""{{ cookiecutter.distribution_name }}: the embodichain task {{ cookiecutter.task_id }}.

Importing this package is cheap; the env lives in :mod:`{{ cookiecutter.package_name }}.task`,
imported when the task is made.
"""

__version__ = "{{ cookiecutter.version }}"
