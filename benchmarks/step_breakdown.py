"""The instrumented pass of ``env_throughput.py``: where an env step's time goes.

It splits the wall time of ``env.step`` into the MuJoCo calls (``Batch.step``,
``Batch.forward``, ``Batch.reset``), the task's own functor code, and the framework's
Python (the env loop, the managers and the entity API the functors call). From that
split it derives a **ceiling**: the ratio to raw stepping the env would reach if the
framework's Python took no time at all, with the task's physics and functors as they
are. A target above the ceiling cannot be met by making the framework faster.

Everything is instrumented in place (the batch object, ``FunctorEntry.func``, entity
methods as instance attributes) and restored afterwards; each timer adds ~0.2 µs.

Example:
    >>> parts = breakdown(env.unwrapped, run_env, run_raw, steps=200, repeats=3)  # doctest: +SKIP
    >>> parts["ceiling_ratio"]  # doctest: +SKIP
"""

from __future__ import annotations

import time
from typing import Any, Callable, Optional

from common import median, time_once

#: The managers whose functors count as the task's code.
FUNCTOR_MANAGERS = ("event_manager", "observation_manager", "reward_manager")


class TimedBatch:
    """Stands in for ``BatchSim.batch``: forwards everything, times step/forward/reset."""

    def __init__(self, batch: Any):
        self._batch = batch
        self.acc = {"step": 0.0, "forward": 0.0, "reset": 0.0}
        self.calls = {"step": 0, "forward": 0, "reset": 0}

    def __getattr__(self, name: str) -> Any:
        return getattr(self._batch, name)

    def _timed(self, name: str, *args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return getattr(self._batch, name)(*args, **kwargs)
        finally:
            self.acc[name] += time.perf_counter() - start
            self.calls[name] += 1

    def step(self, *args: Any, **kwargs: Any) -> Any:
        return self._timed("step", *args, **kwargs)

    def forward(self, *args: Any, **kwargs: Any) -> Any:
        return self._timed("forward", *args, **kwargs)

    def reset(self, *args: Any, **kwargs: Any) -> Any:
        return self._timed("reset", *args, **kwargs)


class _TimedFunctor:
    """A functor that adds its call time to a :class:`FunctorTimer` (attributes pass through,
    so a class functor keeps its ``reset``)."""

    def __init__(self, func: Any, timer: "FunctorTimer"):
        self._func = func
        self._timer = timer

    def __getattr__(self, name: str) -> Any:
        return getattr(self._func, name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        timer = self._timer
        timer.depth += 1
        start = time.perf_counter()
        try:
            return self._func(*args, **kwargs)
        finally:
            timer.depth -= 1
            if timer.depth == 0:
                timer.functors += time.perf_counter() - start


class FunctorTimer:
    """Times the env's event, observation and reward functors, and, inside them, the
    entity API (the ``get_*``/``set_*`` methods of the scene's entities) they call.

    ``functors`` is the seconds spent in functors (entity calls included) and ``entity``
    the seconds of entity calls made from functors (an entity call that calls another
    counts once). Use as a context manager; everything is restored on exit.
    """

    def __init__(self, env: Any):
        self._env = env
        self.functors = 0.0
        self.entity = 0.0
        self.depth = 0  # functor nesting (an event functor may call another)
        self._entity_depth = 0
        self._undo: list[Callable[[], None]] = []

    def reset_counts(self) -> None:
        self.functors = self.entity = 0.0

    def __enter__(self) -> "FunctorTimer":
        for manager in FUNCTOR_MANAGERS:
            for entry in getattr(getattr(self._env, manager, None), "entries", {}).values():
                self._swap(entry, "func", _TimedFunctor(entry.func, self))
        for ent in getattr(self._env.scene, "entities", {}).values():
            for name in dir(type(ent)):
                if name.startswith(("get_", "set_")) and callable(getattr(type(ent), name, None)):
                    self._shadow(ent, name)
        return self

    def __exit__(self, *exc: Any) -> None:
        while self._undo:
            self._undo.pop()()

    def _swap(self, obj: Any, attr: str, value: Any) -> None:
        old = getattr(obj, attr)
        setattr(obj, attr, value)
        self._undo.append(lambda: setattr(obj, attr, old))

    def _shadow(self, ent: Any, name: str) -> None:
        """An instance attribute that times the bound method while a functor runs."""
        method = getattr(ent, name)

        def timed(*args: Any, **kwargs: Any) -> Any:
            if self.depth == 0 or self._entity_depth:
                return method(*args, **kwargs)  # the framework's own call, or nested
            self._entity_depth += 1
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                self._entity_depth -= 1
                self.entity += time.perf_counter() - start

        try:
            ent.__dict__[name] = timed
        except AttributeError:  # no instance dict: leave this entity's methods untimed
            return
        self._undo.append(lambda: ent.__dict__.pop(name, None))


def breakdown(
    env: Any, run_env: Callable[[int], Any], run_raw: Callable[[int], Any], steps: int, repeats: int
) -> Optional[dict[str, Any]]:
    """Time ``repeats`` instrumented runs of ``steps`` env steps (each followed by a raw run).

    ``physics_excess_ms`` (env ``Batch.step`` minus raw ``Batch.step`` per call) is
    physics the env really does more of (cubes pushed and reset keep contacts active)
    plus thread-pool wake-ups after the Python part of the step. Returns ``None`` when
    the env's simulation has no ``batch`` to instrument.
    """
    sim = env.sim
    batch = sim.__dict__.get("batch")
    if batch is None:  # BatchSim changed shape; nothing to instrument
        return None
    timed = TimedBatch(batch)
    keys = ("env", "step", "forward", "reset", "raw", "functors", "entity")
    rows: dict[str, list[float]] = {k: [] for k in keys}
    calls = {"step": 0, "forward": 0, "reset": 0}
    sim.__dict__["batch"] = timed
    try:
        with FunctorTimer(env) as functors:
            for _ in range(max(1, repeats)):
                for k in timed.acc:
                    timed.acc[k] = 0.0
                    timed.calls[k] = 0
                functors.reset_counts()
                rows["env"].append(time_once(lambda: run_env(steps)))
                for k in ("step", "forward", "reset"):
                    rows[k].append(timed.acc[k])
                    calls[k] += timed.calls[k]
                rows["functors"].append(functors.functors)
                rows["entity"].append(functors.entity)
                rows["raw"].append(time_once(lambda: run_raw(steps)))
    finally:
        sim.__dict__["batch"] = batch
    return _summary(rows, calls, steps, max(1, repeats))


def _summary(rows: dict[str, list[float]], calls: dict[str, int], steps: int, repeats: int) -> dict[str, Any]:
    """Per-call medians of the instrumented runs, and the ceiling they imply."""
    per_call = {k: median(v) / steps * 1e3 for k, v in rows.items()}
    python, framework = [], []
    for i in range(len(rows["env"])):
        py = rows["env"][i] - rows["step"][i] - rows["forward"][i] - rows["reset"][i]
        python.append(py / steps * 1e3)
        framework.append((py - rows["functors"][i] + rows["entity"][i]) / steps * 1e3)
    framework_ms = median(framework)
    task_ms = per_call["functors"] - per_call["entity"]
    return {
        "repeats": repeats,
        "env_ms_per_call": per_call["env"],
        "env_batch_step_ms": per_call["step"],
        "env_batch_forward_ms": per_call["forward"],
        "env_batch_reset_ms": per_call["reset"],
        "forward_calls_per_step": calls["forward"] / (repeats * steps),
        "reset_calls_per_step": calls["reset"] / (repeats * steps),
        "env_python_ms": median(python),
        "functors_ms": per_call["functors"],
        "functor_entity_ms": per_call["entity"],
        "task_functor_ms": task_ms,
        "framework_python_ms": framework_ms,
        "raw_ms_per_call": per_call["raw"],
        "physics_excess_ms": per_call["step"] - per_call["raw"],
        "ceiling_ratio": per_call["raw"] / max(per_call["env"] - framework_ms, 1e-9),
    }
