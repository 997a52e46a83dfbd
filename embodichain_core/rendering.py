"""Headless OpenGL backend for MuJoCo rendering, chosen before MuJoCo is imported.

MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is imported. :func:`configure_gl`
runs on ``import embodichain_core.sim`` (before any core module imports
``mujoco``) and picks a headless backend unless the user already set one:

* a user-set ``MUJOCO_GL`` is always respected;
* otherwise ``"egl"`` when ``libEGL`` is found (Mesa EGL on a CPU-only machine,
  the NVIDIA driver's EGL on a GPU),
* else ``"osmesa"`` when ``libOSMesa`` is found,
* else nothing is set, and :func:`create_gl_context` raises
  :class:`RenderingBackendError` naming what to install when the first renderer
  is created (no error at import: a scene without cameras needs no OpenGL).

Example:
    >>> from embodichain_core.rendering import create_gl_context
    >>> ctx = create_gl_context(640, 480)  # doctest: +SKIP
    >>> ctx.make_current()  # doctest: +SKIP
"""

from __future__ import annotations

import ctypes.util
import os
import platform
import sys
from typing import Any, Optional

#: Backends this module may choose, in order of preference.
HEADLESS_BACKENDS = ("egl", "osmesa")
_LIBRARIES = {"egl": "EGL", "osmesa": "OSMesa"}
_INSTALL_HINT = (
    "install a headless OpenGL library: on Debian/Ubuntu run "
    "'apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri' (EGL; also works without a GPU) or "
    "'apt-get install libosmesa6' (OSMesa), or run scripts/setup_env.sh as root; then set "
    "MUJOCO_GL=egl or MUJOCO_GL=osmesa (or leave it unset to let embodichain choose)"
)

_state: dict[str, Any] = {"configured": False, "chosen": None, "user_set": False}


class RenderingBackendError(RuntimeError):
    """No OpenGL backend could create a rendering context."""


def find_backend_libraries() -> dict[str, Optional[str]]:
    """The shared library found for each headless backend (``None`` when missing)."""
    return {name: ctypes.util.find_library(lib) for name, lib in _LIBRARIES.items()}


def configure_gl(environ: Optional[dict] = None) -> Optional[str]:
    """Set ``MUJOCO_GL`` to a working headless backend unless it is already set.

    Runs once per process (later calls return the first answer). When ``mujoco``
    is already imported the variable is still set, for the record, and
    :func:`create_gl_context` loads the chosen backend directly.

    Args:
        environ: the environment to read and write (``os.environ`` by default).

    Returns:
        The backend in effect (``"egl"``, ``"osmesa"``, a user value such as
        ``"glfw"``), or ``None`` when none was found.
    """
    env = os.environ if environ is None else environ
    if _state["configured"] and environ is None:
        return _state["chosen"]
    user = env.get("MUJOCO_GL", "").strip().lower()
    if user:
        chosen, user_set = user, True
    else:
        chosen, user_set = _pick_backend(), False
        if chosen is not None:
            env["MUJOCO_GL"] = chosen
    if environ is None:
        _state.update(configured=True, chosen=chosen, user_set=user_set)
    return chosen


def _pick_backend() -> Optional[str]:
    """``"egl"`` if libEGL is found, else ``"osmesa"`` if libOSMesa is, else ``None``."""
    if platform.system() != "Linux":
        return None  # macOS/Windows: MuJoCo's own default (CGL/WGL/GLFW) works
    found = find_backend_libraries()
    return next((name for name in HEADLESS_BACKENDS if found[name]), None)


def gl_backend() -> Optional[str]:
    """The backend in effect (after :func:`configure_gl`)."""
    configure_gl()
    return os.environ.get("MUJOCO_GL", "").strip().lower() or None


def _context_class(backend: Optional[str]) -> Any:
    """The ``GLContext`` class of ``backend``, imported directly so that it works
    even when ``mujoco`` was imported before :func:`configure_gl` ran."""
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco import GLContext
    return GLContext


def create_gl_context(width: int, height: int) -> Any:
    """Create and make current an offscreen OpenGL context of ``width x height``.

    Raises:
        RenderingBackendError: no backend works; the message names the backend
            tried, the underlying error and what to install.
    """
    backend = gl_backend()
    try:
        context = _context_class(backend)(int(width), int(height))
        context.make_current()
    except Exception as err:  # ImportError, OSError, EGL/OSMesa errors
        found = find_backend_libraries()
        have = ", ".join(f"{k}: {v or 'not found'}" for k, v in found.items())
        how = "set by the user" if _state["user_set"] else "chosen by embodichain"
        raise RenderingBackendError(
            f"cannot create an OpenGL context for MuJoCo rendering (MUJOCO_GL={backend!r}, {how}; "
            f"libraries: {have}): {type(err).__name__}: {err}. To fix: {_INSTALL_HINT}."
        ) from err
    return context


#: Backends whose contexts :func:`release_current` can unbind (so another thread may bind them).
THREADED_BACKENDS = ("egl", "osmesa")


def release_current() -> None:
    """Make no OpenGL context current on this thread (EGL and OSMesa).

    A context is current in at most one thread; after this, another thread can bind the
    one that was current here (``context.as_current()``).

    Raises:
        RenderingBackendError: the backend in effect is not in :data:`THREADED_BACKENDS`.
    """
    backend = gl_backend()
    if backend == "egl":
        from mujoco import egl
        from OpenGL import EGL

        if egl.EGL_DISPLAY is not None:
            EGL.eglMakeCurrent(egl.EGL_DISPLAY, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, EGL.EGL_NO_CONTEXT)
    elif backend == "osmesa":
        from mujoco import osmesa as mj_osmesa
        from OpenGL import GL, osmesa

        osmesa.OSMesaMakeCurrent(None, None, GL.GL_FLOAT, 0, 0)
        mj_osmesa._current_context.ref = None
    else:
        raise RenderingBackendError(
            f"cannot release an OpenGL context of MUJOCO_GL={backend!r} for another thread; "
            f"use one of {', '.join(THREADED_BACKENDS)}"
        )


def mujoco_imported_first() -> bool:
    """True when ``mujoco`` was imported before :func:`configure_gl` (diagnostics)."""
    return "mujoco" in sys.modules and not _state["configured"]
