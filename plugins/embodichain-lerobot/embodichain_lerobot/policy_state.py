"""One policy state per env slot, with batched inference through the policy's own ``select_action``.

LeRobot policies keep their rollout state batch-wide: ACT one action queue of ``(B, A)``
rows (or a temporal ensembler), diffusion a queue of observations and one of actions, all
cleared together by ``policy.reset()``. When env ``i`` of a batch ends its episode, only its
state must start over. :class:`PerEnvPolicy` keeps the state (the attributes ``reset()``
sets, e.g. ``_action_queue``, ``_queues``, ``temporal_ensembler``) for groups of env slots
whose states have the same structure (queue lengths, shapes, shared values), each as the
policy holds it for a batch of the group's size. A step runs the policy's ``select_action``
once per group on the group's rows of the batch. A reset takes the reset envs' rows out of
their groups into a fresh group; groups whose states come to match are merged again. Envs
that started their episodes together stay one group (one batched call, no state copied);
an env reset mid-chunk re-plans on its own at its next step."""

from __future__ import annotations

import copy
from collections import deque
from typing import Any, Callable, Hashable

import torch

__all__ = ["PerEnvPolicy"]

_MODULE_ATTRS = frozenset(vars(torch.nn.Module()))
_SMALL = 256  # shared tensors up to this size are compared by value when grouping


class _Row:
    """The rows ``(m, ...)`` of a batched state tensor that belong to a group (or a slot)."""

    __slots__ = ("t",)

    def __init__(self, t: torch.Tensor):
        self.t = t


def _is_plain_object(value: Any) -> bool:
    return hasattr(value, "__dict__") and not isinstance(value, (torch.nn.Module, type)) and not callable(value)


def _map(value: Any, leaf: Callable[[Any, tuple], Any], path: tuple = ()) -> Any:
    """``value`` with every tensor (and :class:`_Row`) replaced by ``leaf(x, path)``;
    containers and plain objects (an ensembler) are rebuilt, everything else kept."""
    if isinstance(value, (torch.Tensor, _Row)):
        return leaf(value, path)
    if isinstance(value, deque):
        return deque((_map(v, leaf, (*path, "[]")) for v in value), maxlen=value.maxlen)
    if isinstance(value, dict):
        return {k: _map(v, leaf, (*path, k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_map(v, leaf, (*path, j)) for j, v in enumerate(value))
    if _is_plain_object(value):
        obj = copy.copy(value)
        obj.__dict__ = _map(vars(value), leaf, path)
        return obj
    return value


def _wrap(state: dict[str, Any], m: int, shared: set) -> dict[str, Any]:
    """A group's state (batch of ``m``) with its batched tensors marked as :class:`_Row`.

    A tensor is batched when its first dim is ``m``, unless its path is in ``shared`` (a
    tensor of the fresh state, or one found not batched before, which is then added).
    """

    def leaf(t: Any, path: tuple) -> Any:
        if isinstance(t, torch.Tensor) and t.ndim and t.shape[0] == m and path not in shared:
            return _Row(t)
        shared.add(path)
        return t

    return {k: _map(v, leaf, (k,)) for k, v in state.items()}


def _row(wrapped: Any, i: int) -> Any:
    """Slot ``i``'s state in a wrapped group state."""
    return _map(wrapped, lambda x, _: _Row(x.t[i : i + 1]) if isinstance(x, _Row) else x)


def _merge(values: list[Any]) -> Any:
    """One state (as the policy holds it) from wrapped states of groups that fit together."""
    first = values[0]
    if isinstance(first, deque):
        return deque((_merge(list(items)) for items in zip(*values)), maxlen=first.maxlen)
    if isinstance(first, dict):
        return {k: _merge([v[k] for v in values]) for k in first}
    if isinstance(first, (list, tuple)):
        return type(first)(_merge(list(items)) for items in zip(*values))
    if isinstance(first, _Row):
        return torch.cat([v.t for v in values], dim=0)
    if isinstance(first, torch.Tensor):
        return first.clone()  # shared: equal in every group merged
    if _is_plain_object(first):
        obj = copy.copy(first)
        obj.__dict__ = _merge([vars(v) for v in values])
        return obj
    return first


def _tensor_paths(state: dict[str, Any]) -> set:
    """The paths of the tensors in a state (see :func:`_wrap`)."""
    paths: set = set()
    for key, value in state.items():
        _map(value, lambda t, path: paths.add(path), (key,))
    return paths


def _signature(value: Any) -> Hashable:
    """What must be equal for two slots to run in one batch."""
    if isinstance(value, deque):
        return ("deque", value.maxlen, tuple(_signature(v) for v in value))
    if isinstance(value, dict):
        return ("dict", tuple((str(k), _signature(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, tuple(_signature(v) for v in value))
    if isinstance(value, _Row):
        return ("row", tuple(value.t.shape[1:]), str(value.t.dtype))
    if isinstance(value, torch.Tensor):
        data = value.detach().cpu().numpy().tobytes() if value.numel() <= _SMALL else None
        return ("tensor", tuple(value.shape), str(value.dtype), data)
    if _is_plain_object(value):
        return (type(value).__qualname__, _signature(vars(value)))
    try:
        hash(value)
        return ("value", value)
    except TypeError:
        return ("object", type(value).__qualname__)


def _rows(batch: dict[str, Any], ids: list[int], size: int) -> dict[str, Any]:
    """The sub-batch of rows ``ids`` of a batch of ``size`` (the batch itself for all rows in order)."""
    if ids == list(range(size)):
        return batch
    out: dict[str, Any] = {}
    for key, value in batch.items():
        if isinstance(value, torch.Tensor) and value.ndim and value.shape[0] == size:
            out[key] = value[torch.as_tensor(ids, device=value.device)]
        elif isinstance(value, list) and len(value) == size:
            out[key] = [value[i] for i in ids]
        else:
            out[key] = value
    return out


class PerEnvPolicy:
    """A LeRobot policy driving ``num_envs`` envs, each with its own rollout state.

    The envs are kept in groups whose states fit together, each group's state as the policy
    holds it for a batch of the group's size. A step runs the policy once per group; a reset
    takes the reset envs' rows out of their groups into a fresh group; groups whose states
    have come to match are merged again.

    Args:
        policy: a ``PreTrainedPolicy`` (its ``reset()`` defines what the state is).
        num_envs: the number of env slots.
    """

    def __init__(self, policy: Any, num_envs: int):
        self.policy = policy
        self.num_envs = int(num_envs)
        policy.reset()
        self.keys = [k for k in vars(policy) if k not in _MODULE_ATTRS and k != "config"]
        self._fresh = {k: copy.deepcopy(getattr(policy, k)) for k in self.keys}
        self._shared = _tensor_paths(self._fresh)  # constants such as ensemble weights
        self._groups: list[tuple[list[int], dict[str, Any]]] = [
            (list(range(self.num_envs)), copy.deepcopy(self._fresh))
        ]

    def state_of(self, env_id: int) -> dict[str, Any]:
        """The rollout state of env ``env_id``, as the policy would hold it for a batch of one."""
        for ids, state in self._groups:
            if env_id in ids:
                return _merge([_row(_wrap(state, len(ids), self._shared), ids.index(env_id))])
        raise IndexError(f"env {env_id} is not one of the {self.num_envs} envs")

    def groups(self) -> list[list[int]]:
        """The env slots that run together, sorted."""
        return sorted(sorted(ids) for ids, _ in self._groups)

    def reset(self, env_ids: Any = None) -> None:
        """Start the state of the envs ``env_ids`` (default: all) over."""
        reset = set(range(self.num_envs)) if env_ids is None else {int(i) for i in env_ids}
        if not reset:
            return
        groups = []
        for ids, state in self._groups:
            keep = [j for j, i in enumerate(ids) if i not in reset]
            if len(keep) == len(ids):
                groups.append((ids, state))
            elif keep:
                wrapped = _wrap(state, len(ids), self._shared)
                groups.append(([ids[j] for j in keep], _merge([_row(wrapped, j) for j in keep])))
        groups.append((sorted(reset), copy.deepcopy(self._fresh)))
        self._groups = groups
        self._coalesce()

    def _coalesce(self) -> None:
        """Merge the groups whose states fit together."""
        if len(self._groups) < 2:
            return
        buckets: dict[Hashable, list[tuple[list[int], dict[str, Any]]]] = {}
        for ids, state in self._groups:
            wrapped = _wrap(state, len(ids), self._shared)
            buckets.setdefault(_signature(wrapped), []).append((ids, wrapped))
        if len(buckets) == len(self._groups):
            return
        self._groups = [
            (sum((ids for ids, _ in members), []), _merge([w for _, w in members])) for members in buckets.values()
        ]

    @torch.inference_mode()
    def select_action(self, batch: dict[str, Any]) -> torch.Tensor:
        """One action per env, ``(num_envs, A)``, from a preprocessed batch of ``num_envs`` rows."""
        out: torch.Tensor | None = None
        for g, (ids, state) in enumerate(self._groups):
            for key in self.keys:
                setattr(self.policy, key, state[key])
            action = self.policy.select_action(_rows(batch, ids, self.num_envs))
            self._groups[g] = (ids, {key: getattr(self.policy, key) for key in self.keys})
            if out is None:
                out = action.new_zeros((self.num_envs, *action.shape[1:]))
            out[torch.as_tensor(ids, device=out.device)] = action
        self._coalesce()
        assert out is not None
        return out
