"""The ``embodichain`` command line (:func:`embodichain_core.cli.main.main`).

Subcommands come from the ``commands`` registry, filled by the core's built-ins
and by plugins (``embodichain_register_commands``); each is imported only when run.
"""
