"""Viewers of embodichain-core envs: MuJoCo's native passive window and a Viser browser page.

The plugin registers both through the ``embodichain_register_viewers`` hook
(:mod:`embodichain_viewer.plugin`); the core opens the one ``sim_cfg.viewer`` selects when
``sim_cfg.headless`` is false (:mod:`embodichain_core.viewing`), and
:func:`embodichain_viewer.session.open_session` attaches it to a built env.
"""

__version__ = "0.1.0"
