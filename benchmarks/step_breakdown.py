"""Where an env step's time goes: the instrumented pass of ``env_throughput.py``, and a
phase profiler of ``PushCube-v1`` on any backend and device (run as a script).

Library use (``env_throughput.py``): :func:`breakdown` splits the wall time of ``env.step``
on the CPU batch backend into the MuJoCo calls (``Batch.step``, ``Batch.forward``,
``Batch.reset``), the task's own functor code, and the framework's Python (the env loop,
the managers and the entity API the functors call). From that split it derives a
**ceiling**: the ratio to raw stepping the env would reach if the framework's Python took
no time at all, with the task's physics and functors as they are. A target above the
ceiling cannot be met by making the framework faster. Everything is instrumented in place
(the batch object, ``BuiltFunctor.func``, entity methods as instance attributes) and
restored afterwards; each timer adds ~0.2 µs.

Script use: ``--task`` (``PushCube-v1`` by default) on ``--backend``/``--device``, per
``--num-envs``, after an untimed warm-up (the first step on a GPU compiles MuJoCo Warp's
kernels):

- ``plain``: env steps/s of the uninstrumented loop;
- ``phases``: each phase of ``EmbodiedEnv.step`` (physics: ``sim.advance``), a few calls inside them and every
  event/observation/reward functor, each call bracketed by two device syncs
  (:class:`gpu_step_profile.PhaseTimer`);
- ``syncs``: the calls per step that make the host wait for the device, and the lines that
  make them (:class:`gpu_step_profile.SyncCounter`);
- ``cprofile`` and ``torch_profiler``: the functions and ops with the most time.

Each timed window is ``--steps`` env steps (100 by default: one episode of PushCube-v1, so
it holds one auto-reset of every env). Results are written after every section, so a run cut short
keeps what it measured.

Usage:
    python benchmarks/step_breakdown.py [--task PushCube-v1] [--backend warp] [--device cuda]
        [--num-envs 1024 4096] [--steps 100] [--episode-length N] [--warmup 20] [--profile-steps 10] [--budget-s 0] [--out PATH] [--smoke]

Example:
    >>> parts = breakdown(env.unwrapped, run_env, run_raw, steps=200, repeats=3)  # doctest: +SKIP
    >>> parts["ceiling_ratio"]  # doctest: +SKIP
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any, Callable, Optional

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from common import machine_info, median, print_table, time_once, write_json  # noqa: E402
from gpu_step_profile import FUNCTOR_MANAGERS, PhaseTimer, SyncCounter, cprofile_top, torch_profile  # noqa: E402


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


# -- the script -------------------------------------------------------------------------------------
def make_env(
    num_envs: int, backend: str, device: str, episode_length: Optional[int] = None, task: str = "PushCube-v1"
) -> Any:
    """``task`` (a registered ``EmbodiedEnv``) on ``backend``/``device``, reset once;
    ``episode_length`` replaces its ``max_episode_steps`` (``None``: the task's own)."""
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    import embodichain_core  # noqa: F401  (loads the plugins and their tasks)

    entry = gym.spec(task).entry_point
    env_cls: Any = load_env_creator(entry) if isinstance(entry, str) else entry
    cfg = env_cls.cfg_cls()
    cfg.sim_cfg.backend = backend
    cfg.sim_cfg.sim_device = device
    if episode_length is not None:
        cfg.max_episode_steps = episode_length
    env = gym.make(task, cfg=cfg, num_envs=num_envs, seed=0, verbose=False).unwrapped
    env.reset(seed=0)
    return env


def _stepper(env: Any, cuda: bool) -> tuple[Callable[[int], None], Callable[[], None]]:
    """``(run(steps), sync)``: ``steps`` env steps of 50 cycled random actions on the env's
    device, uniform over the middle half of the action space (a Box; bounds clipped to
    [-1, 1])."""
    import torch

    low, high = (torch.as_tensor(b, dtype=torch.float32) for b in (env.action_space.low, env.action_space.high))
    mid, half = (high.clamp(max=1.0) + low.clamp(min=-1.0)) / 2, (high.clamp(max=1.0) - low.clamp(min=-1.0)) / 2
    gen = torch.Generator().manual_seed(0)
    shape = env.action_space.shape
    actions = [(mid + 0.5 * half * (torch.rand(shape, generator=gen) * 2 - 1)).to(env.device) for _ in range(50)]
    sync = torch.cuda.synchronize if cuda else (lambda: None)

    def run(steps: int) -> None:
        for t in range(steps):
            env.step(actions[t % len(actions)])
        sync()

    return run, sync


def _sections(env: Any, args: argparse.Namespace, cuda: bool) -> dict[str, Callable[[], Any]]:
    """The script's sections (see the module docstring), by name, in order."""
    run, sync = _stepper(env, cuda)
    n = env.num_envs

    def plain() -> dict[str, Any]:
        times = [time_once(lambda: run(args.steps)) for _ in range(2)]
        return {
            "times_s": times,
            "step_ms": median(times) / args.steps * 1e3,
            "env_steps_per_s": n * args.steps / median(times),
        }

    def phases() -> dict[str, Any]:
        with PhaseTimer(env, sync) as timer:
            wall = time_once(lambda: run(args.steps))
        return timer.summary(args.steps, wall)

    def syncs() -> dict[str, Any]:
        with SyncCounter(cuda) as counter:
            run(args.steps)
        return counter.summary(args.steps)

    return {
        "warmup": lambda: {"seconds": time_once(lambda: run(args.warmup)), "steps": args.warmup},
        "plain": plain,
        "phases": phases,
        "syncs": syncs,
        "cprofile": lambda: cprofile_top(run, args.steps),
        "torch_profiler": lambda: torch_profile(run, args.profile_steps, cuda),
    }


def measure(args: argparse.Namespace, num_envs: int, save: Callable[[dict], None], start: float) -> dict[str, Any]:
    """Every section at ``num_envs`` envs (skipped once ``--budget-s`` has passed since ``start``);
    ``save(row)`` after each."""
    built = time.perf_counter()
    env = make_env(num_envs, args.backend, args.device, args.episode_length, args.task)
    row: dict[str, Any] = {"num_envs": num_envs, "build_s": time.perf_counter() - built}
    cuda = getattr(env.device, "type", str(env.device)).startswith("cuda")
    for name, section in _sections(env, args, cuda).items():
        if args.budget_s and time.perf_counter() - start > args.budget_s:
            row[name] = {"skipped": f"past --budget-s {args.budget_s}"}
            continue
        print(f"[{num_envs} envs] {name} ...", flush=True)
        try:
            row[name] = section()
        except Exception as err:  # keep the other sections' numbers
            row[name] = {"error": f"{type(err).__name__}: {err}"}
        save(row)
    env.close()
    return row


def _device_info(device: str) -> dict[str, Any]:
    """Versions of the GPU stack, and the GPU on a CUDA ``device``."""
    info: dict[str, Any] = {}
    for module in ("warp", "mujoco_warp", "gymnasium"):
        try:
            info[module] = __import__(module).__version__
        except Exception:  # pragma: no cover - reporting only
            info[module] = None
    import torch

    if device.startswith("cuda") and torch.cuda.is_available():
        props = torch.cuda.get_device_properties(0)
        info["gpu"] = f"{props.name} ({props.total_memory / 2**30:.0f} GiB)"
    return info


def parse_args(argv: Optional[list[str]] = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description="Where an env step's time goes (see the module docstring).")
    p.add_argument("--task", default="PushCube-v1", help="a registered EmbodiedEnv task id")
    p.add_argument("--backend", default="warp", help="sim_cfg.backend: warp or mujoco_batch")
    p.add_argument("--device", default="cuda", help="sim_cfg.sim_device: cuda, cuda:N or cpu")
    p.add_argument("--num-envs", type=int, nargs="+", default=[1024, 4096])
    p.add_argument("--steps", type=int, default=100, help="env steps per timed window (default: one episode)")
    p.add_argument("--episode-length", type=int, default=None, help="max_episode_steps (default: the task's own)")
    p.add_argument("--warmup", type=int, default=20, help="untimed env steps first (GPU: kernels compile)")
    p.add_argument("--profile-steps", type=int, default=10, help="env steps under the torch profiler")
    p.add_argument(
        "--budget-s", type=float, default=0.0, help="skip the sections left after this many seconds (0: none)"
    )
    p.add_argument("--out", default=os.path.join("benchmarks", "results", "step_breakdown.json"))
    p.add_argument("--smoke", action="store_true", help="warp on cpu, 4 envs, 4-step episodes (checks this script)")
    args = p.parse_args(argv)
    if args.smoke:
        args.backend, args.device, args.num_envs = "warp", "cpu", [4]
        args.steps, args.episode_length, args.warmup, args.profile_steps = 4, 4, 2, 2
    if min(args.steps, args.profile_steps, args.episode_length or 1, *args.num_envs) < 1 or args.warmup < 0:
        p.error("--steps, --profile-steps, --episode-length and --num-envs must be positive, --warmup not negative")
    return args


def main(argv: Optional[list[str]] = None) -> dict[str, Any]:
    args = parse_args(argv)
    start = time.perf_counter()
    payload: dict[str, Any] = {
        "benchmark": "step_breakdown",
        "settings": vars(args),
        "machine": machine_info() | _device_info(args.device),
        "results": [],
    }

    def save(row: dict) -> None:
        if not any(r is row for r in payload["results"]):
            payload["results"].append(row)
        if args.out:
            write_json(args.out, payload)

    for n in args.num_envs:
        measure(args, n, save, start)
    rows = [
        {"num_envs": r["num_envs"], "phase": k, "ms": v["ms"]}
        for r in payload["results"]
        for k, v in (r.get("phases", {}).get("phases") or {}).items()
    ]
    print_table(rows, [("num_envs", "num_envs", "d"), ("phase", "phase", "s"), ("ms", "ms per env step", ".2f")])
    if args.out:
        print(f"wrote {args.out}")
    return payload


if __name__ == "__main__":
    main()
