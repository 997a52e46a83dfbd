"""Per-episode random streams: each env's draws are a function of its episode alone.

Every env slot owns a counter-based stream keyed by its current *episode seed*. By
default the episode seed is derived from ``(seed, env index, episode index)``, where the
episode index counts that env's resets since the env was seeded. So one env's extra
reset (a divergence, an early success), a different ``num_envs`` or a different number
of workers never changes another env's draws. A caller that owns episode identities
(distributed generation) passes explicit seeds with
``env.reset(options={"reset_ids": ids, "episode_seeds": seeds})``; the recorder stores
each episode's seed, so any episode can be replayed alone on any env slot.

Why a counter-based stream written here: numpy's generators are one object per stream,
and seeding one (``SeedSequence``) for each of 64 env resets would cost more than the
whole randomized reset. Here a draw for any set of envs is a handful of vectorized
uint64 operations: element ``p`` of a stream with key ``k`` is ``mix64(k + (p + 1) * γ)``,
SplitMix64's output function (Steele, Lea & Flood, "Fast splittable pseudorandom
number generators", OOPSLA 2014), the same construction as numpy's own ``SeedSequence``
mixing and JAX's counter-based keys.

Example:
    >>> rng = EpisodeRandom(num_envs=3, seed=0)
    >>> rng.begin_episodes(np.arange(3))
    >>> rng.uniform([0, 2], 0.0, 1.0, shape=(2,)).shape
    (2, 2)
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

__all__ = ["EpisodeRandom", "derive_seed", "episode_seeds_option", "STARTUP_EPISODE"]

_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = (np.uint64(s) for s in (30, 27, 31, 11))
_TO_UNIT = 2.0**-53
#: Episode index of the stream startup events draw from (before the first episode).
STARTUP_EPISODE = 2**64 - 1


def _mix(x: np.ndarray) -> np.ndarray:
    """SplitMix64's output function, in place on a uint64 array (wrapping arithmetic)."""
    x ^= x >> _S30
    x *= _M1
    x ^= x >> _S27
    x *= _M2
    x ^= x >> _S31
    return x


def _as_u64(values: Any, what: str) -> np.ndarray:
    arr = np.asarray(values)
    if arr.dtype == np.uint64:
        return arr.reshape(-1).copy()
    if arr.dtype.kind not in "iu" and arr.size:
        raise TypeError(f"{what} must be integers, got dtype {arr.dtype}")
    arr = arr.astype(np.int64, copy=False).reshape(-1) if arr.dtype.kind == "i" else arr.reshape(-1)
    if arr.dtype.kind == "i" and (arr < 0).any():
        raise ValueError(f"{what} must be >= 0, got {arr[arr < 0][:4].tolist()}")
    return arr.astype(np.uint64)


def derive_seed(seed: int, *keys: Any) -> np.ndarray:
    """The episode seed(s) of ``(seed, *keys)``: a uint64 hash chain, vectorized over keys.

    ``derive_seed(s, env_ids, episode_ids)`` is what an env uses for its episodes;
    a distributed generator uses ``derive_seed(s, k)`` for global episode ``k``.

    Args:
        seed: the run's seed (a non-negative int below 2**64).
        keys: ints or integer arrays (broadcast together), e.g. env and episode indices.

    Returns:
        A uint64 array of the broadcast shape of ``keys`` (0-d for scalar keys).
    """
    if not 0 <= int(seed) < 2**64:
        raise ValueError(f"seed must be in [0, 2**64), got {seed}")
    arrays = [_as_u64(k, "episode keys").reshape(np.shape(k)) for k in keys]
    return _chain(int(seed), np.broadcast_arrays(*arrays) if arrays else [])


def _chain(seed: int, keys: Sequence[np.ndarray]) -> np.ndarray:
    """The hash chain of :func:`derive_seed` over uint64 arrays of one shape."""
    shape = keys[0].shape if len(keys) else ()
    h = np.full((1,) + shape, np.uint64(seed), dtype=np.uint64)  # 1-D+: wrapping without scalar warnings
    h += _GAMMA
    _mix(h)
    for key in keys:
        h += (key.reshape((1,) + shape) + np.uint64(1)) * _GAMMA
        _mix(h)
    return h.reshape(shape)


class EpisodeRandom:
    """Random streams of ``num_envs`` env slots, one stream per episode.

    Draw methods take ``env_ids`` (any int sequence, tensor or ``None`` for every env)
    and return one row per id, each row drawn from that env's stream.

    Args:
        num_envs: number of env slots.
        seed: the run's seed.
    """

    def __init__(self, num_envs: int, seed: int):
        self.num_envs = int(num_envs)
        self._all = np.arange(self.num_envs)
        self.episode_seeds = np.zeros(self.num_envs, dtype=np.uint64)
        self.episode_index = np.zeros(self.num_envs, dtype=np.int64)
        self._state = np.zeros(self.num_envs, dtype=np.uint64)  # SplitMix64 state per slot
        self._steps: np.ndarray = np.zeros(0, dtype=np.uint64)  # (1..m) * γ, grown on demand
        self.seed(seed, startup=True)

    def seed(self, seed: int, *, startup: bool = False) -> None:
        """Reseed: the next episode of each env is its episode 0 under ``seed``.

        Episodes already running keep their streams until their env resets. With
        ``startup``, every slot switches to its startup stream (what startup events
        draw from, before the first episode).
        """
        if not 0 <= int(seed) < 2**64:
            raise ValueError(f"seed must be in [0, 2**64), got {seed}")
        self.base_seed = int(seed)
        self.episode_index[:] = 0
        # the chain of derive_seed(seed, env, episode) up to the env: one mix per episode start
        self._env_keys = _chain(self.base_seed, [self._all.astype(np.uint64)])
        if startup:
            tag = np.full(self.num_envs, np.uint64(STARTUP_EPISODE), dtype=np.uint64)
            self._start(self._all, _chain(self.base_seed, [self._all.astype(np.uint64), tag]))

    def begin_episodes(self, env_ids: Any, seeds: Optional[Sequence[int]] = None) -> None:
        """Start a new episode on ``env_ids``, from ``seeds`` or derived ones.

        Args:
            env_ids: the env slots whose new episode starts.
            seeds: one explicit episode seed per id (ints in ``[0, 2**64)``); by default
                ``derive_seed(seed, env_id, episode_index)``.
        """
        ids = self._ids(env_ids)
        if seeds is None:  # derive_seed(seed, ids, episode_index[ids]), from the cached env links
            new = self._env_keys[ids]  # a copy (fancy index)
            new += (self.episode_index[ids].astype(np.uint64) + np.uint64(1)) * _GAMMA
            _mix(new)
        else:
            new = _as_u64(seeds, "episode_seeds")
            if new.shape != ids.shape:
                raise ValueError(f"episode_seeds has {new.size} values for {ids.size} reset env(s)")
        self.episode_index[ids] += 1
        self._start(ids, new)

    def _start(self, ids: np.ndarray, seeds: np.ndarray) -> None:
        self.episode_seeds[ids] = seeds
        self._state[ids] = _mix(seeds + _GAMMA)

    def _ids(self, env_ids: Any) -> np.ndarray:
        if env_ids is None:
            return self._all
        if isinstance(env_ids, np.ndarray) and env_ids.dtype == np.int64 and env_ids.ndim == 1:
            return env_ids
        ids = env_ids.cpu().numpy() if hasattr(env_ids, "cpu") else np.asarray(env_ids)  # a CPU tensor: shared
        if ids.dtype != np.int64 or ids.ndim != 1:
            ids = ids.astype(np.int64).reshape(-1)
        return ids

    def bits(self, env_ids: Any, shape: Sequence[int] = ()) -> np.ndarray:
        """Raw uint64 draws, shape ``(len(env_ids), *shape)``; advances each stream."""
        ids = self._ids(env_ids)
        shape = tuple(shape)
        m = 1
        for size in shape:
            m *= int(size)
        if m > self._steps.size:
            self._steps = np.arange(1, max(m, 64) + 1, dtype=np.uint64) * _GAMMA
        state = self._state[ids]
        x = np.add(state[:, None], self._steps[:m])
        if m:
            state += self._steps[m - 1]
            self._state[ids] = state
        _mix(x)
        return x if len(shape) == 1 else x.reshape((ids.size,) + shape)

    def random(self, env_ids: Any, shape: Sequence[int] = ()) -> np.ndarray:
        """Floats in ``[0, 1)`` (float64, 53 random bits), shape ``(len(env_ids), *shape)``."""
        x = self.bits(env_ids, shape)
        x >>= _S11
        return np.multiply(x, _TO_UNIT)  # uint64 -> float64 inside the ufunc

    def uniform(self, env_ids: Any, low: Any, high: Any, shape: Optional[Sequence[int]] = None) -> np.ndarray:
        """Floats in ``[low, high)``; ``shape`` defaults to the broadcast shape of the bounds."""
        low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
        shape = np.broadcast_shapes(low.shape, high.shape) if shape is None else tuple(shape)
        out = self.random(env_ids, shape)
        out *= high - low
        out += low
        return out

    def integers(self, env_ids: Any, high: int, shape: Sequence[int] = ()) -> np.ndarray:
        """Integers in ``[0, high)`` (int64), shape ``(len(env_ids), *shape)``."""
        if int(high) < 1:
            raise ValueError(f"integers: high must be >= 1, got {high}")
        return np.minimum((self.random(env_ids, shape) * int(high)).astype(np.int64), int(high) - 1)

    def normal(self, env_ids: Any, shape: Sequence[int] = (), loc: Any = 0.0, scale: Any = 1.0) -> np.ndarray:
        """Gaussian draws (Box-Muller on two uniforms per value)."""
        shape = tuple(int(s) for s in shape)
        u = self.random(env_ids, (2,) + shape)
        radius = np.sqrt(-2.0 * np.log1p(-u[:, 0]))
        return loc + scale * radius * np.cos(2.0 * np.pi * u[:, 1])


def episode_seeds_option(options: dict, n_reset: int) -> Optional[np.ndarray]:
    """``options["episode_seeds"]`` of ``env.reset`` checked against the reset ids.

    Raises:
        ValueError: not one non-negative int below 2**64 per reset env (naming the option).
    """
    seeds = options.get("episode_seeds")
    if seeds is None:
        return None
    try:
        arr = np.asarray([int(s) for s in np.asarray(seeds, dtype=object).reshape(-1)], dtype=object)
        if any(not 0 <= s < 2**64 for s in arr):
            raise ValueError("out of range")
        values = arr.astype(np.uint64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"reset option 'episode_seeds' must hold ints in [0, 2**64), got {seeds!r}") from None
    if values.size != n_reset:
        raise ValueError(
            f"reset option 'episode_seeds' has {values.size} value(s) for {n_reset} reset env(s) "
            f"(one per id of 'reset_ids', in the same order)"
        )
    return values
