"""Simulation layer (scene, batch, entities). Importing it chooses the headless
OpenGL backend (``MUJOCO_GL``) before any of its modules imports MuJoCo."""

from embodichain_core.rendering import configure_gl as _configure_gl

_configure_gl()
