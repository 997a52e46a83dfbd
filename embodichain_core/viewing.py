"""Which viewer a non-headless env opens, and attaching it (``sim_cfg.headless: false``).

``sim_cfg.viewer`` (``--viewer``) is one of :data:`VIEWER_MODES`: ``auto`` picks MuJoCo's
native window when a display is available (``DISPLAY`` or ``WAYLAND_DISPLAY`` set) and the
browser viewer otherwise; ``native`` and ``browser`` force one; ``none`` opens nothing.
Plugins provide the viewers through the ``embodichain_register_viewers`` hook
(:class:`~embodichain_core.plugins.hookspecs.ViewerRegister`); :func:`viewer_opener` looks
one up. With ``headless: true`` (or ``viewer: none``) no viewer module is imported, and when
no installed plugin provides the viewer asked for, a non-headless env stops with one message
naming the viewers that are registered and what to install.

Example:
    >>> resolve_viewer_mode("auto", {"DISPLAY": ":0"})
    'native'
    >>> resolve_viewer_mode("auto", {})
    'browser'
"""

from __future__ import annotations

import contextlib
import os
from typing import Any, Callable, Iterator, Mapping, Optional

from embodichain_core.config.errors import ConfigError
from embodichain_core.plugins import failed_plugins, viewer_registry
from embodichain_core.plugins.hookspecs import VIEWER_NAMES, hook_name
from embodichain_core.plugins.registry import AmbiguousNameError, Registry, TargetImportError, join_names
from embodichain_core.utils.suggest import did_you_mean

#: Values of ``sim_cfg.viewer`` / ``--viewer``.
VIEWER_MODES = ("auto", *VIEWER_NAMES, "none")
#: What a missing viewer's message tells to install.
INSTALL_ADVICE = (
    f"install a plugin that registers viewers (hook {hook_name('viewers')}; the 'Installing' section of "
    "the viewer documentation, viewer.md, names one), then check it with `embodichain list viewers`"
)
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
        ConfigError: a bad ``sim_cfg.viewer``, or no plugin provides that viewer (:func:`viewer_opener`).
    """
    sim_cfg = env.cfg.sim_cfg
    if _forced is None and getattr(sim_cfg, "headless", True):
        return None
    mode = resolve_viewer_mode(_forced or str(getattr(sim_cfg, "viewer", "auto")))
    if mode == "none":
        return None
    opener = viewer_opener(mode)
    return opener(env, mode, port=int(getattr(sim_cfg, "viewer_port", 8080)))


def viewer_opener(name: str) -> Callable[..., Any]:
    """The opener a plugin registered for viewer ``name`` (``"native"`` or ``"browser"``), imported.

    Raises:
        ConfigError: at ``sim_cfg.headless``: no installed plugin registers that viewer (the message
            names the viewers that are registered and what to install), several do, or its module
            fails to import. Each message also offers running headless.
    """
    registry = viewer_registry()
    try:
        entry = registry.find(name)
        if entry is not None:
            return entry.resolve()
        problem = _missing(registry, name)
    except AmbiguousNameError as err:
        problem = (
            f"several plugins register it ({join_names(err.providers)}); keep one of them installed, or "
            "block the others with EMBODICHAIN_BLOCK_PLUGINS"
        )
    except TargetImportError as err:
        problem = str(err)
    raise ConfigError(
        "sim_cfg.headless",
        f"headless: false opens the {name} viewer, but {problem}; or run headless (--headless / --viewer none)",
    )


def _missing(registry: Registry, name: str) -> str:
    """Why no ``name`` viewer is there: the viewers registered, the plugins that failed, what to install."""
    entries = registry.entries()
    have = (
        "the viewers registered are " + join_names([f"{e.name} ({e.provider})" for e in entries])
        if entries
        else "no viewers are registered"
    )
    failed = [plugin for plugin, _ in failed_plugins()]
    if failed:
        have += f"; plugins that failed to load: {join_names(failed)} (`embodichain list plugins -v`)"
    return f"no installed plugin registers it ({have}); {INSTALL_ADVICE}"
