"""Simulation layer: object configs (``cfg``, ``shapes``), the ``Scene`` and its entities,
data paths, the sensor base class; ``backend/`` (the simulation interface ``SimBackend``
and its ``mujoco.batch`` implementation) and ``scene_build/`` (configs to one compiled
``MjModel``). See docs/architecture.md.

Importing it chooses the headless OpenGL backend (``MUJOCO_GL``) before any of its
modules imports MuJoCo.
"""

from embodichain_core.rendering import configure_gl as _configure_gl

_configure_gl()
