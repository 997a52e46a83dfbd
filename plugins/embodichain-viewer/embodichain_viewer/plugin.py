"""The plugin's registrations: the two viewers a non-headless env opens (``sim_cfg.viewer``).

Both openers are ``"module:function"`` strings, so loading the plugin imports neither viser
nor MuJoCo's viewer: :func:`embodichain_viewer.session.open_session` is imported the first
time an env opens a viewer.
"""

from __future__ import annotations

from embodichain_core.plugins import ViewerRegister, hookimpl

#: name (``sim_cfg.viewer``) -> description.
VIEWERS = {
    "native": "MuJoCo's native window (needs a display)",
    "browser": "a Viser page served on localhost (no display needed)",
}


@hookimpl
def embodichain_register_viewers(register: ViewerRegister) -> None:
    """Register the native and the browser viewer (one opener serves both)."""
    for name, description in VIEWERS.items():
        register(name, "embodichain_viewer.session:open_session", description=description)
