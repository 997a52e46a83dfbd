"""Which model fields the ``warp`` backend can give per-env values, and what to recompute.

MuJoCo Warp batches a model field per world when its array spec starts with ``"*"``
(leading dim 1 = shared, ``num_envs`` = one row per world). :func:`field_kind` sorts a
``mujoco.MjModel`` field name into:

* ``"world"``: batched on the device (``body_mass``, ``geom_friction``, ``dof_damping``,
  ``opt.gravity``...);
* ``"host"``: a visual field MuJoCo Warp does not simulate (``light_intensity``...): kept
  per env on the host, seen by the CPU renderer through ``sim.get_model(i)``;
* anything else fails with :func:`unsupported` (collision filters, solver type, mesh
  data, structural ints): a :class:`~embodichain_core.config.errors.ConfigError` naming
  the field and the backend.

:data:`CONST_GROUPS` maps the fields MuJoCo derives constants from to the
``mujoco_warp.set_const`` groups that recompute them, and :data:`GROUP_OUTPUTS` the
fields each group writes (they are expanded along with their inputs: ``set_const``
writes row ``world % rows``).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import mujoco

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean

#: ``set_const`` group bits (``mujoco_warp.SetConstGroup``: FIXED, KIN0, INERT0).
FIXED, KIN0, INERT0 = 1, 2, 4
ALL = FIXED | KIN0 | INERT0

#: Constant inputs -> the groups to recompute after a write (others of
#: ``MjModel._setconst_inputs``: :data:`ALL`).
CONST_GROUPS: dict[str, int] = {
    "body_mass": ALL,
    "body_inertia": INERT0,
    "body_ipos": ALL,
    "body_iquat": INERT0,
    "body_pos": ALL,
    "body_quat": ALL,
    "dof_armature": INERT0,
    "actuator_armature": INERT0,
    "actuator_gear": INERT0,
    "tendon_armature": INERT0,
    "qpos0": KIN0 | INERT0,
    "geom_size": FIXED,
    "cam_pos": KIN0,
    "cam_quat": KIN0,
    "light_pos": KIN0,
    "light_dir": KIN0,
    "eq_data": KIN0,
    "body_gravcomp": 0,
    "geom_pos": 0,
    "geom_quat": 0,
}
#: Fields each group writes (only those MuJoCo Warp batches).
GROUP_OUTPUTS: dict[int, tuple[str, ...]] = {
    FIXED: ("body_subtreemass", "geom_aabb", "geom_rbound"),
    KIN0: (
        "tendon_length0",
        "eq_data",
        "cam_pos0",
        "cam_poscom0",
        "cam_mat0",
        "light_pos0",
        "light_poscom0",
        "light_dir0",
    ),
    INERT0: ("dof_invweight0", "body_invweight0", "tendon_invweight0", "actuator_acc0"),
}
#: Prefixes of visual fields kept per env on the host when MuJoCo Warp has no such field.
HOST_PREFIXES = ("light_", "mat_", "tex_", "cam_", "skin_")
_SETCONST_INPUTS = frozenset(mujoco.MjModel._setconst_inputs)


def _batched(cls: Any) -> frozenset[str]:
    from mujoco_warp._src import warp_util

    names = set()
    for f in dataclasses.fields(cls):
        if warp_util.is_array_spec(f.type) and tuple(getattr(f.type, "shape", ()))[:1] == ("*",):
            names.add(f.name)
    return frozenset(names)


@functools.lru_cache(maxsize=None)
def batched_fields() -> frozenset[str]:
    """The model fields (``opt.*`` for options) MuJoCo Warp batches per world."""
    from mujoco_warp._src import types

    return _batched(types.Model) | {f"opt.{n}" for n in _batched(types.Option)}


@functools.lru_cache(maxsize=None)
def warp_fields() -> frozenset[str]:
    """Every field name of MuJoCo Warp's ``Model`` (batched or not)."""
    from mujoco_warp._src import types

    return frozenset(f.name for f in dataclasses.fields(types.Model))


def field_kind(name: str, model: mujoco.MjModel) -> str:
    """``"world"``, ``"host"`` or ``"unsupported"`` for ``MjModel`` field ``name``."""
    if name in batched_fields():
        return "world"
    known = hasattr(model, name) or (name.startswith("opt.") and hasattr(model.opt, name[4:]))
    if known and name not in warp_fields() and name.startswith(HOST_PREFIXES):
        return "host"
    return "unsupported"


def unsupported(name: str, model: mujoco.MjModel) -> ConfigError:
    """The build-time error for a per-env write of ``name`` that the warp backend cannot do."""
    if name in ("geom_contype", "geom_conaffinity"):
        why = (
            "MuJoCo Warp computes the colliding geom pairs once, for every world; per-env mesh variants "
            "(reserve_mesh_variants/reserve_scale_variants) switch them"
        )
    elif name.startswith("opt."):
        why = "MuJoCo Warp's solver, integrator, iterations, cone and flags are one value for every world"
    elif name.startswith(("mesh_", "hfield_", "geom_type")):
        why = "mesh geometry is shared by every world (only a choice among compiled meshes could vary)"
    elif hasattr(model, name):
        why = "MuJoCo Warp does not batch this field per world"
    else:
        return ConfigError(
            "sim_cfg.backend", f"unknown model field {name!r}.{did_you_mean(name, sorted(batched_fields()))}"
        )
    return ConfigError(
        "sim_cfg.backend",
        f"model field {name!r} cannot take per-env values on backend "
        f"'warp' ({why}); use backend 'mujoco_batch' for this scene",
    )


def const_groups(name: str) -> int:
    """The ``set_const`` groups a write of ``name`` needs (0: none)."""
    if name in CONST_GROUPS:
        return CONST_GROUPS[name]
    return ALL if name in _SETCONST_INPUTS else 0


def derived_outputs(name: str) -> tuple[str, ...]:
    """The batched fields ``set_const`` writes after a write of ``name``."""
    groups = const_groups(name)
    return tuple(out for bit, outs in GROUP_OUTPUTS.items() if groups & bit for out in outs)
