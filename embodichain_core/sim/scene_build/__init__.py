"""Scene building: configs to one compiled ``MjModel``.

``builder`` (the ``MjSpec`` of a scene, uids, lights, ground), ``builder_articulation``
and ``builder_objects`` (robots/articulations and rigid objects into the spec),
``articulation_loader`` and ``model_source`` (URDF/MJCF to a spec), ``mesh`` and
``convex`` (mesh loading, convex decomposition with a disk cache), ``variants``
(per-env mesh and scale variants compiled into one model). Nothing here steps a
simulation; :mod:`embodichain_core.sim.backend` does. Importing this package is
cheap (no MuJoCo, trimesh or coacd until a module that needs them is imported).
"""
