"""Instruments for profiling an env's step on any backend and device (used by ``step_breakdown.py``).

- :class:`PhaseTimer` times the phases of ``EmbodiedEnv.step`` (:data:`STEP_PHASES`), the
  calls in :data:`STEP_DETAILS` and every event/observation/reward functor, each call
  between two device syncs (so queued GPU work is charged to the phase that queued it).
- :class:`SyncCounter` counts the calls that make the host wait for the device, under the
  first frame of the project's code that made them: the torch ops that
  ``torch.cuda.set_sync_debug_mode("warn")`` reports (device->host reads such as
  ``.tolist()``, ``.cpu()``, ``bool(tensor)``, ``nonzero``, and copies from pageable host
  memory such as a CUDA tensor indexed by a CPU index tensor) and Warp's own waits
  (``wp.synchronize*``, ``wp.array.numpy``).
- :func:`torch_profile` sums the torch profiler's events per step: the CUDA runtime calls
  that copy or wait (``cudaMemcpyAsync``, ``cudaStreamSynchronize``...), kernel launches,
  the ops with the most host time, and the GPU's kernel time.
- :func:`cprofile_top` is cProfile's view: the functions with the most own and total time.

Example:
    >>> with SyncCounter(cuda=True) as syncs:  # doctest: +SKIP
    ...     run(10)
    >>> syncs.summary(10)["per_step"]  # doctest: +SKIP
"""

from __future__ import annotations

import cProfile
import pstats
import re
import time
import traceback
import warnings
from collections import Counter, defaultdict
from typing import Any, Callable

import torch

#: The managers whose functors count as the task's code.
FUNCTOR_MANAGERS = ("event_manager", "observation_manager", "reward_manager")
#: Frames of these packages count as the project's code (plugins map to plugins/<dist>/).
_PROJECT = re.compile(r"(embodichain_\w+)/(.+\.py)$")
#: The torch profiler's events that copy device memory or wait for the device.
SYNC_EVENTS = re.compile(
    r"^(cudaMemcpy|cudaStreamSynchronize|cudaDeviceSynchronize|cudaEventSynchronize|cuMemcpy|cuStreamSynchronize|cuCtxSynchronize|cuEventSynchronize)"
)
LAUNCH_EVENTS = re.compile(r"^(cudaLaunchKernel|cuLaunchKernel|cudaGraphLaunch|cuGraphLaunch|cudaLaunchKernelExC)")
_WARP_WAITS = ("synchronize", "synchronize_device", "synchronize_stream", "synchronize_event")


def repo_path(filename: str) -> str | None:
    """``embodichain_core/x.py`` or ``plugins/embodichain-tasks/embodichain_tasks/x.py`` for
    a frame of the project's code (installed or in the tree), else ``None``."""
    match = _PROJECT.search(filename.replace("\\", "/"))
    if match is None:
        return None
    package, rest = match.groups()
    return (
        f"{package}/{rest}"
        if package == "embodichain_core"
        else f"plugins/{package.replace('_', '-')}/{package}/{rest}"
    )


def call_site(depth: int = 3) -> str:
    """The innermost project frame of the current stack (``path:line  code``), with up to
    ``depth - 1`` project callers after ``<-``."""
    sites: list[str] = []
    for frame in reversed(traceback.extract_stack()[:-2]):
        path = repo_path(frame.filename)
        if path is not None:
            sites.append(f"{path}:{frame.lineno}" + ("" if sites else f"  {(frame.line or '').strip()}"))
            if len(sites) == depth:
                break
    return " <- ".join(sites) if sites else "(outside the project)"


class SyncCounter:
    """Counts the calls of a block that make the host wait for the device, by kind and call
    site (see the module docstring).

    Torch's sync check reports only on CUDA; Warp's waits are counted on every device.
    Other warnings raised in the block are kept in :attr:`other_warnings`.
    """

    def __init__(self, cuda: bool):
        self.cuda = cuda
        self.sites: Counter[tuple[str, str]] = Counter()
        self.other_warnings: Counter[str] = Counter()
        self._undo: list[Callable[[], None]] = []

    def record(self, kind: str) -> None:
        self.sites[(kind, call_site())] += 1

    def _show(self, message: Any, category: Any, filename: str, lineno: int, *args: Any, **kwargs: Any) -> None:
        text = str(message)
        if "synchroniz" in text:
            self.record("torch")
        else:
            self.other_warnings[f"{category.__name__}: {text[:160]}"] += 1

    def _patch_warp(self) -> None:
        try:
            import warp as wp
        except ImportError:
            return
        for name in _WARP_WAITS:
            self._wrap(wp, name, f"warp.{name}")
        self._wrap(wp.array, "numpy", "warp.array.numpy")

    def _wrap(self, owner: Any, name: str, kind: str) -> None:
        original = getattr(owner, name, None)
        if original is None:
            return

        def counted(*args: Any, **kwargs: Any) -> Any:
            self.record(kind)
            return original(*args, **kwargs)

        setattr(owner, name, counted)
        self._undo.append(lambda: setattr(owner, name, original))

    def __enter__(self) -> "SyncCounter":
        catcher = warnings.catch_warnings()
        catcher.__enter__()
        self._undo.append(lambda: catcher.__exit__(None, None, None))
        warnings.simplefilter("always")
        warnings.showwarning = self._show
        if self.cuda:
            torch.cuda.set_sync_debug_mode("warn")
            self._undo.append(lambda: torch.cuda.set_sync_debug_mode("default"))
        self._patch_warp()
        return self

    def __exit__(self, *exc: Any) -> None:
        while self._undo:
            self._undo.pop()()

    def summary(self, steps: int) -> dict[str, Any]:
        """Syncs per step by kind, and the sites (most frequent first) with their per-step counts."""
        kinds: Counter[str] = Counter()
        for (kind, _), n in self.sites.items():
            kinds[kind] += n
        return {
            "per_step": sum(kinds.values()) / steps,
            "per_step_by_kind": {k: n / steps for k, n in kinds.most_common()},
            "sites": [
                {"kind": kind, "site": site, "per_step": n / steps} for (kind, site), n in self.sites.most_common()
            ],
            "other_warnings": dict(self.other_warnings.most_common(10)),
        }


def _device_us(event: Any, self_only: bool) -> float:
    names = (
        ("self_device_time_total", "self_cuda_time_total") if self_only else ("device_time_total", "cuda_time_total")
    )
    for name in names:
        if hasattr(event, name):
            return float(getattr(event, name))
    return 0.0


def torch_profile(run: Callable[[int], Any], steps: int, cuda: bool, top: int = 25) -> dict[str, Any]:
    """The torch profiler over ``run(steps)``: per-step counts and times (ms) of sync/copy
    calls, launches, the ``top`` ops by own host time, and the GPU's kernel time."""
    from torch.profiler import ProfilerActivity, profile

    activities = [ProfilerActivity.CPU] + ([ProfilerActivity.CUDA] if cuda else [])
    with profile(activities=activities) as prof:
        run(steps)
    events = prof.key_averages()

    def row(e: Any) -> dict[str, Any]:
        return {
            "name": e.key[:120],
            "calls_per_step": e.count / steps,
            "self_host_ms_per_step": e.self_cpu_time_total / steps / 1e3,
            "host_ms_per_step": e.cpu_time_total / steps / 1e3,
            "device_ms_per_step": _device_us(e, False) / steps / 1e3,
        }

    host = [e for e in events if e.self_cpu_time_total > 0]
    kernels = [e for e in events if _device_us(e, True) > 0 and e.self_cpu_time_total == 0]
    return {
        "steps": steps,
        "sync_and_copy_calls": [row(e) for e in events if SYNC_EVENTS.match(e.key)],
        "launch_calls": [row(e) for e in events if LAUNCH_EVENTS.match(e.key)],
        "top_host_ops": [row(e) for e in sorted(host, key=lambda e: -e.self_cpu_time_total)[:top]],
        "device_kernel_ms_per_step": sum(_device_us(e, True) for e in kernels) / steps / 1e3,
        "top_kernels": [row(e) for e in sorted(kernels, key=lambda e: -_device_us(e, True))[:10]],
    }


def _where(key: tuple[str, int, str]) -> str:
    filename, line, func = key
    path = repo_path(filename)
    if path is None:
        path = filename.rsplit("site-packages/", 1)[-1].rsplit("/tmp/site/", 1)[-1]
    return f"{path}:{line}({func})" if line else f"{func}"


def cprofile_top(run: Callable[[int], Any], steps: int, top: int = 30) -> dict[str, Any]:
    """cProfile over ``run(steps)``: the ``top`` functions by own time (any code) and the
    ``top`` project functions by total time, in ms per step."""
    profiler = cProfile.Profile()
    profiler.enable()
    try:
        run(steps)
    finally:
        profiler.disable()
    stats = pstats.Stats(profiler).stats  # type: ignore[attr-defined]

    def row(key: Any, value: Any) -> dict[str, Any]:
        _, calls, own, total, _ = value
        return {
            "function": _where(key),
            "calls_per_step": calls / steps,
            "own_ms_per_step": own / steps * 1e3,
            "total_ms_per_step": total / steps * 1e3,
        }

    items = list(stats.items())
    by_own = sorted(items, key=lambda kv: -kv[1][2])[:top]
    project = [kv for kv in items if repo_path(kv[0][0]) is not None]
    by_total = sorted(project, key=lambda kv: -kv[1][3])[:top]
    return {
        "steps": steps,
        "by_own_time": [row(*kv) for kv in by_own],
        "project_by_total_time": [row(*kv) for kv in by_total],
    }


# -- phases of EmbodiedEnv.step, each call between two device syncs (any backend) ------------------
#: ``(phase, owner on the env ('' = the env itself), method)``: the top-level phases of
#: ``EmbodiedEnv.step``, in order. A phase called from another (``get_obs`` inside the
#: auto-reset) counts in the outer one.
STEP_PHASES = (
    ("check_action", "", "_check_action"),
    ("action_terms", "action_manager", "process_action"),
    ("apply_command", "", "apply_action"),
    ("physics", "sim", "advance"),  # the env's physics call (sim.advance: every env, diverged mask back)
    ("interval_events", "event_manager", "apply"),
    ("observations", "", "get_obs"),
    ("info", "", "get_info"),
    ("reward", "", "_reward"),
    ("dones", "", "_dones"),
    ("auto_reset", "", "_auto_reset"),
)
#: Calls inside the phases timed on their own (besides every functor).
STEP_DETAILS = (
    ("physics.failure_check", "sim", "_failed_mask"),  # backend warp: the divergence check on the device
    ("observations.robot_state", "_robot_io", "observe"),
    ("auto_reset.scene_reset", "scene", "reset"),
)
_MISSING = object()


class _Synced:
    """A method or functor timed by a :class:`PhaseTimer`; attributes pass through."""

    def __init__(self, func: Any, timer: "PhaseTimer", kind: str, key: str):
        self._func, self._timer, self._kind, self._key = func, timer, kind, key

    def __getattr__(self, name: str) -> Any:
        return getattr(self._func, name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._timer.call(self._kind, self._key, self._func, args, kwargs)


class PhaseTimer:
    """Times the :data:`STEP_PHASES` of an env's ``step``, the :data:`STEP_DETAILS` and the
    event/observation/reward functors, each call between two ``sync()`` calls. Use as a
    context manager; everything is restored on exit."""

    def __init__(self, env: Any, sync: Callable[[], None]):
        self._env, self._sync = env, sync
        self.seconds: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
        self.calls: dict[str, Counter[str]] = defaultdict(Counter)
        self._in_phase = False
        self._undo: list[Callable[[], None]] = []

    def call(self, kind: str, key: str, func: Any, args: tuple, kwargs: dict) -> Any:
        outer = kind == "phase"
        if outer and self._in_phase:
            return func(*args, **kwargs)
        self._in_phase |= outer
        self._sync()
        start = time.perf_counter()
        try:
            return func(*args, **kwargs)
        finally:
            self._sync()
            self.seconds[kind][key] += time.perf_counter() - start
            self.calls[kind][key] += 1
            if outer:
                self._in_phase = False

    def __enter__(self) -> "PhaseTimer":
        for kind, table in (("phase", STEP_PHASES), ("detail", STEP_DETAILS)):
            for key, path, method in table:
                owner = self._env
                for part in filter(None, path.split(".")):
                    owner = getattr(owner, part, None)
                if owner is not None and callable(getattr(owner, method, None)):
                    self._shadow(owner, method, _Synced(getattr(owner, method), self, kind, key))
        for manager in FUNCTOR_MANAGERS:
            for name, entry in getattr(getattr(self._env, manager, None), "entries", {}).items():
                key = f"{manager.removesuffix('_manager')}.{name}"
                self._shadow(entry, "func", _Synced(entry.func, self, "functor", key))
        return self

    def _shadow(self, owner: Any, name: str, value: Any) -> None:
        old = vars(owner).get(name, _MISSING)
        setattr(owner, name, value)
        self._undo.append(lambda: delattr(owner, name) if old is _MISSING else setattr(owner, name, old))

    def __exit__(self, *exc: Any) -> None:
        while self._undo:
            self._undo.pop()()

    def summary(self, steps: int, wall: float) -> dict[str, Any]:
        """ms per env step of each timed call (and calls per step); ``unattributed_ms`` is the
        step's time outside every phase."""

        def table(kind: str) -> dict[str, dict[str, float]]:
            rows = sorted(self.seconds[kind].items(), key=lambda kv: -kv[1])
            return {k: {"ms": v / steps * 1e3, "calls": self.calls[kind][k] / steps} for k, v in rows}

        phases = table("phase")
        step_ms = wall / steps * 1e3
        return {
            "step_ms": step_ms,
            "phases": phases,
            "unattributed_ms": step_ms - sum(p["ms"] for p in phases.values()),
            "details": table("detail"),
            "functors": table("functor"),
        }
