"""Per-env model fields of :class:`~embodichain_core.sim.backend.warp_sim.WarpSim`.

A field written per env is first *expanded*: its shared ``(1, ...)`` MuJoCo Warp array is
replaced by a ``(num_envs, ...)`` one (with the fields ``set_const`` derives from it,
:func:`~embodichain_core.sim.backend.warp_fields.derived_outputs`), and the step's graphs
are dropped so that the next step captures the new arrays. Declare the fields at setup
(:meth:`WarpModelFields.declare_per_env`) to keep that off the episode loop. Writes go in
place through a torch view of the array; the constants they feed are recomputed once, by
``mujoco_warp.set_const`` over every world, before the next step, forward or host copy
(the groups of every write since the last one, together).

The backend owns one :class:`WarpModelFields` (``sim.fields``) and forwards the model-field
methods of the interface to it; the fields object reads the backend's MuJoCo Warp model and
data, and clears its graphs, through the references it is given at construction.
"""

from __future__ import annotations

import copy
from typing import Any, Iterable, Optional

import mujoco
import numpy as np
import torch

from embodichain_core.sim.backend.env_rows import field_selector, np_ids
from embodichain_core.sim.backend.warp_device import StepGraphs
from embodichain_core.sim.backend.warp_fields import ALL, const_groups, derived_outputs, field_kind, unsupported


class WarpModelFields:
    """The model fields of ``num_envs`` MuJoCo Warp worlds: which hold per-env values, and
    the constants due after writes.

    Args:
        model: the host ``MjModel`` template (shared values, shapes).
        wp: the ``warp`` module.
        mjw: the ``mujoco_warp`` module.
        wp_model, wp_data: the worlds' MuJoCo Warp model and data (``wp_model``'s arrays are
            replaced in place when a field is expanded).
        graphs: the backend's step graphs (cleared when an array is replaced).
    """

    def __init__(self, model: mujoco.MjModel, wp: Any, mjw: Any, wp_model: Any, wp_data: Any, graphs: StepGraphs):
        self.model = model
        self.num_envs = int(wp_data.nworld)
        self._wp, self._mjw = wp, mjw
        self._wp_model, self._wp_data = wp_model, wp_data
        self._graphs = graphs
        self._expanded: set[str] = set()
        self._views: dict[str, torch.Tensor] = {}
        self._shared: dict[str, torch.Tensor] = {}  # device copies of shared fields (model_tensor)
        self._host: dict[str, np.ndarray] = {}  # visual fields MuJoCo Warp does not hold
        self.mirrored: set[str] = set()
        """Host fields whose writer also folds their effect into a field MuJoCo Warp batches
        (the Light entity writes its intensity into ``light_diffuse`` too): MuJoCo Warp's
        renderer shows them all the same."""
        self._const_groups = 0

    # -- arrays ----------------------------------------------------------------------------------
    def _owner(self, name: str) -> tuple[Any, str]:
        if name.startswith("opt."):
            return self._wp_model.opt, name[4:]
        return self._wp_model, name

    def _template(self, name: str) -> np.ndarray:
        if name.startswith("opt."):
            return np.asarray(getattr(self.model.opt, name[4:]))
        return np.asarray(getattr(self.model, name))

    def _expand(self, name: str) -> None:
        """Give field ``name`` one row per world (a new array; the graphs are re-captured)."""
        obj, attr = self._owner(name)
        arr = getattr(obj, attr, None)
        if name in self._expanded or arr is None:
            return
        if arr.shape[0] != self.num_envs:
            rows = np.repeat(arr.numpy()[:1], self.num_envs, axis=0)
            new = self._wp.array(rows, dtype=arr.dtype, device=self._graphs.device)
            new._is_batched = True
            setattr(obj, attr, new)
            self._graphs.clear()
        self._expanded.add(name)
        self._views.pop(name, None)
        self._shared.pop(name, None)

    def _view(self, name: str) -> torch.Tensor:
        """``(num_envs, ...)`` torch view of an expanded field, shaped as in ``MjModel``."""
        view = self._views.get(name)
        if view is None:
            obj, attr = self._owner(name)
            view = self._wp.to_torch(getattr(obj, attr))
            shape = (self.num_envs,) + self._template(name).shape
            if view.numel() == int(np.prod(shape)):
                view = view.view(shape)
            self._views[name] = view
        return view

    # -- the interface ---------------------------------------------------------------------------
    def declare_per_env(self, names: Iterable[str]) -> None:
        """Expand fields (and what ``set_const`` derives from them) now, before graph capture.

        Raises:
            ConfigError: a field this backend cannot hold per env (names it and the backend).
        """
        for name in names:
            kind = field_kind(name, self.model)
            if kind == "unsupported":
                raise unsupported(name, self.model)
            if kind == "world":
                for field in (name,) + derived_outputs(name):
                    self._expand(field)

    @property
    def host_fields(self) -> list[str]:
        """The fields holding per-env values on the host only (visual fields MuJoCo Warp
        does not hold: the CPU renderer reads them, MuJoCo Warp's renderer does not), sorted."""
        return sorted(self._host)

    @property
    def unrendered_fields(self) -> list[str]:
        """The :attr:`host_fields` MuJoCo Warp's renderer would not show (not :attr:`mirrored`)."""
        return sorted(set(self._host) - self.mirrored)

    def is_per_env(self, name: str) -> bool:
        """Whether ``name`` holds per-env values (expanded, or a host-side visual field)."""
        return name in self._expanded or name in self._host

    def model_field(self, name: str) -> np.ndarray:
        """Read-only ``(num_envs, ...)`` values (float32 where per env, else the template's)."""
        if name in self._host:
            values = self._host[name]
        elif name in self._expanded:
            values = self._view(name).detach().cpu().numpy()
        else:
            base = self._template(name)
            return np.broadcast_to(base, (self.num_envs,) + base.shape)
        values = values.view()
        values.flags.writeable = False
        return values

    def model_tensor(self, name: str, device: torch.device) -> torch.Tensor:
        """``(num_envs, ...)`` values on ``device``: the torch view of a per-env field, a copy
        of a shared field made once (until it is expanded), host-side visual values copied."""
        if name in self._expanded:
            return self._view(name)
        if name in self._host:
            return torch.as_tensor(np.array(self._host[name]), device=device)
        shared = self._shared.get(name)
        if shared is None:
            base = torch.as_tensor(np.array(self._template(name)), device=device)
            shared = self._shared[name] = base.expand((self.num_envs,) + tuple(base.shape))
        return shared

    def set_model_field(self, name: str, env_ids: Any, index: Any, values: Any, set_const: bool = True) -> None:
        """Write ``values`` into ``name[index]`` of each env (see the interface); a field
        MuJoCo Warp cannot batch raises :class:`ConfigError`."""
        kind = field_kind(name, self.model)
        if kind == "unsupported":
            raise unsupported(name, self.model)
        ids = np_ids(env_ids, self.num_envs)
        if isinstance(values, torch.Tensor):
            values = values.detach().cpu().numpy()
        if kind == "host":
            if name not in self._host:
                self._host[name] = np.repeat(self._template(name)[None], self.num_envs, axis=0)
            self._host[name][field_selector(ids, index)] = values
            return
        self.declare_per_env([name])
        view = self._view(name)
        sel = tuple(
            torch.as_tensor(s, device=view.device) if isinstance(s, np.ndarray) else s
            for s in field_selector(ids, index)
        )
        view[sel] = torch.as_tensor(np.array(values), dtype=view.dtype, device=view.device)
        if set_const:
            self._const_groups |= const_groups(name)

    def set_body_masses(self, env_ids: Any, bodies: Any, mass: Any) -> None:
        """Masses ``(n, k)`` of ``bodies``; their inertias scale along (one recompute)."""
        rows = np_ids(env_ids, self.num_envs)
        bodies = np.asarray(bodies, dtype=np.int64).reshape(-1)
        mass = np.broadcast_to(np.asarray(mass, dtype=np.float64), (len(rows), len(bodies)))
        sel = (rows[:, None], bodies[None, :])
        ratio = (mass / np.maximum(self.model_field("body_mass")[sel], 1e-12))[..., None]
        inertia = self.model_field("body_inertia")[sel] * ratio
        self.set_model_field("body_inertia", rows, bodies, inertia, set_const=False)
        self.set_model_field("body_mass", rows, bodies, mass)

    def mark_const_dirty(self, fields: Optional[Iterable[tuple[str, Any]]] = None) -> None:
        """Schedule the recompute of the constants of ``fields`` (``(name, index)`` pairs;
        every group if unknown), for every world."""
        if fields is None:
            self._const_groups |= ALL
            return
        for name, _ in fields:
            self._const_groups |= const_groups(name)

    def flush_const(self) -> None:
        """Run ``mujoco_warp.set_const`` once for every group written since the last flush
        (over every world: MuJoCo Warp has no subset; unchanged worlds get the same values)."""
        if not self._const_groups:
            return
        groups, self._const_groups = self._const_groups, 0
        with self._wp.ScopedDevice(self._graphs.device):
            self._mjw.set_const(self._wp_model, self._wp_data, groups=self._mjw.SetConstGroup(groups))

    # -- host copies -----------------------------------------------------------------------------
    def get_model(self, env_id: int, model: Optional[mujoco.MjModel] = None) -> mujoco.MjModel:
        """Env ``env_id``'s model on the host: the template with that env's per-env rows
        (pass ``model``, a copy of ``self.model``, to fill it in place)."""
        self.flush_const()
        model = copy.copy(self.model) if model is None else model
        env = int(env_id)
        for name in sorted(self._expanded | set(self._host)):
            row = self.model_field(name)[env]
            if name.startswith("opt."):
                setattr(model.opt, name[4:], row if np.ndim(row) else row.item())
            elif hasattr(model, name) and getattr(model, name).shape == row.shape:
                getattr(model, name)[...] = row
        return model
