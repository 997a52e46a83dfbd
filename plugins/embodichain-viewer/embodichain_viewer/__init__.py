"""Viewers of embodichain-core envs: MuJoCo's native passive window and a Viser browser page.

The core opens one when ``sim_cfg.headless`` is false (:mod:`embodichain_core.viewing`);
:func:`embodichain_viewer.session.open_session` attaches it to a built env.
"""

__version__ = "0.1.0"
