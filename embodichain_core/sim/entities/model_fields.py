"""Per-env model fields of articulations and the scene: the values users randomize.

Every setter writes through the simulation interface (``sim.set_model_field``), so each
env keeps its own value; a field first written per env stops being shared.

**Shape contract** of every per-joint (per-link) setter, for ``n`` envs (``env_ids``) and
``k`` joints (``joint_ids``) or links (``link_names``), numpy broadcasting to ``(n, k)``:

* a number: every env and joint;
* ``(k,)``: one value per joint, the same in every env;
* ``(n, k)``: per env and joint; ``(n, 1)``: per env, the same for every joint;
* ``(n,)`` when it cannot be per joint (``n != k``, or ``k == 1``): per env.

Anything else is a ``ValueError`` naming the expected shapes. Getters return
``(n, k)`` float32 tensors. Gravity (:func:`set_gravity`) is ``(3,)`` or ``(n, 3)``.

Example:
    >>> robot.set_joint_damping(torch.linspace(0.5, 5.0, 4)[:, None], joint_ids=[0, 1])  # doctest: +SKIP
    >>> robot.get_joint_damping(joint_ids=[0, 1])[:, 0]  # doctest: +SKIP
    tensor([0.5000, 2.0000, 3.5000, 5.0000])
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from embodichain_core.sim.entities.base import env_index

if TYPE_CHECKING:
    pass

_GRAVITY = "opt.gravity"


def per_env_values(values: Any, n: int, k: int, what: str = "values") -> np.ndarray:
    """``values`` as a float64 ``(n, k)`` array following the shape contract (module doc).

    Raises:
        ValueError: a shape that does not broadcast, naming ``what`` and the valid shapes.
    """
    if isinstance(values, torch.Tensor):
        values = values.detach().cpu().numpy()
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == n and (n != k or k == 1):
        arr = arr[:, None]
    try:
        return np.broadcast_to(arr, (n, k))
    except ValueError:
        raise ValueError(
            f"{what}: got shape {arr.shape}; expected a number, ({k},) per joint/link, "
            f"({n}, {k}) per env and joint/link, ({n}, 1) or ({n},) per env"
        ) from None


def set_gravity(sim: Any, gravity: Any, env_ids: Any = None) -> None:
    """Gravity per env: ``(3,)`` for every env in ``env_ids``, or ``(n, 3)``.

    Raises:
        ValueError: a bad shape, or a backend where gravity is one global option.
    """
    env = env_index(env_ids, sim.num_envs).numpy()
    vals = np.asarray(gravity.detach().cpu().numpy() if isinstance(gravity, torch.Tensor) else gravity, dtype=float)
    try:
        vals = np.broadcast_to(vals, (len(env), 3))
    except ValueError:
        raise ValueError(f"gravity: got shape {vals.shape}; expected (3,) or ({len(env)}, 3)") from None
    if not len(env):
        return
    try:
        sim.set_model_field(_GRAVITY, env, Ellipsis, vals)
    except (AttributeError, KeyError, ValueError) as err:
        raise ValueError(
            f"gravity is a global option on this simulation backend (per-env gravity is "
            f"unavailable here: {err}); set physics_config.gravity in the config instead"
        ) from err
    sim.mark_dirty(env)


def get_gravity(sim: Any, env_ids: Any = None) -> torch.Tensor:
    """(n, 3) gravity of ``env_ids``."""
    env = env_index(env_ids, sim.num_envs).numpy()
    if sim.is_per_env(_GRAVITY):
        try:
            return torch.as_tensor(np.array(sim.model_field(_GRAVITY)[env]), dtype=torch.float32)
        except (AttributeError, KeyError) as err:
            raise ValueError(f"gravity is a global option on this simulation backend: {err}") from err
    return torch.as_tensor(np.array(sim.model.opt.gravity), dtype=torch.float32).expand(len(env), 3).clone()
