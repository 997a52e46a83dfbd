"""Which viewer a non-headless env opens, and attaching it (``sim_cfg.headless: false``).

``sim_cfg.viewer`` (``--viewer``) is one of :data:`VIEWER_MODES`: ``auto`` picks MuJoCo's
native window when a display is available (``DISPLAY`` or ``WAYLAND_DISPLAY`` set) and the
browser viewer otherwise; ``native`` and ``browser`` force one; ``none`` opens nothing.
The viewers live in the ``embodichain-viewer`` plugin: with ``headless: true`` (or
``viewer: none``) nothing of it is imported, and when it is missing a non-headless env
stops with one message naming the install command.

Example:
    >>> resolve_viewer_mode("auto", {"DISPLAY": ":0"})
    'native'
    >>> resolve_viewer_mode("auto", {})
    'browser'
"""

from __future__ import annotations

import contextlib
import os
from typing import Any, Iterator, Mapping, Optional

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean

#: Values of ``sim_cfg.viewer`` / ``--viewer``.
VIEWER_MODES = ("auto", "native", "browser", "none")
#: The command that installs the viewers (printed when they are missing).
INSTALL_HINT = "pip install -e plugins/embodichain-viewer  (or: pip install embodichain-viewer)"
_forced: Optional[str] = None  # set by force_viewer()


def has_display(environ: Optional[Mapping[str, str]] = None) -> bool:
    """Whether a desktop display is reachable (``DISPLAY`` or ``WAYLAND_DISPLAY`` set)."""
    env = os.environ if environ is None else environ
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def resolve_viewer_mode(mode: str, environ: Optional[Mapping[str, str]] = None) -> str:
    """The viewer to open for ``mode``: ``"native"``, ``"browser"`` or ``"none"``.

    Args:
        mode: one of :data:`VIEWER_MODES`.
        environ: the environment to look for a display in (default ``os.environ``).

    Raises:
        ConfigError: ``sim_cfg.viewer`` is not a mode, or is ``native`` without a display.
    """
    if mode not in VIEWER_MODES:
        raise ConfigError("sim_cfg.viewer", f"unknown viewer {mode!r}.{did_you_mean(str(mode), VIEWER_MODES)}")
    if mode == "auto":
        return "native" if has_display(environ) else "browser"
    if mode == "native" and not has_display(environ):
        raise ConfigError(
            "sim_cfg.viewer",
            "the native viewer needs a display and neither DISPLAY nor WAYLAND_DISPLAY is set; "
            "use --viewer browser (a page served on localhost) on a machine without one",
        )
    return mode


@contextlib.contextmanager
def force_viewer(mode: Optional[str]) -> Iterator[None]:
    """Within the block, every env built opens ``mode``'s viewer whatever its ``sim_cfg``
    says (``"none"``: none); ``None`` changes nothing. For commands that build their envs
    deep inside a library (``train-rl --play --viewer``).

    Raises:
        ConfigError: ``mode`` is not one of :data:`VIEWER_MODES`.
    """
    global _forced
    if mode is not None and mode not in VIEWER_MODES:
        raise ConfigError("viewer", f"unknown viewer {mode!r}.{did_you_mean(str(mode), VIEWER_MODES)}")
    previous, _forced = _forced, mode if mode is not None else _forced
    try:
        yield
    finally:
        _forced = previous


def attach_viewer(env: Any) -> Optional[Any]:
    """Open the viewer ``env.cfg.sim_cfg`` asks for; ``None`` (nothing imported) when headless.

    Args:
        env: a built :class:`~embodichain_core.envs.embodied_env.EmbodiedEnv`.

    Returns:
        The viewer session (``before_step()``, ``after_step(obs, reward, info)``,
        ``close()``), or ``None``.

    Raises:
        ConfigError: a bad ``sim_cfg.viewer``, or the viewer plugin is not installed.
    """
    sim_cfg = env.cfg.sim_cfg
    if _forced is None and getattr(sim_cfg, "headless", True):
        return None
    mode = resolve_viewer_mode(_forced or str(getattr(sim_cfg, "viewer", "auto")))
    if mode == "none":
        return None
    try:
        from embodichain_viewer.session import open_session
    except ImportError as err:
        raise ConfigError(
            "sim_cfg.headless",
            f"headless: false opens a viewer, which needs the embodichain-viewer plugin ({err}); "
            f"install it with: {INSTALL_HINT}; or run headless (--headless / --viewer none)",
        ) from None
    return open_session(env, mode, port=int(getattr(sim_cfg, "viewer_port", 8080)))
