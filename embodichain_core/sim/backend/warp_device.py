"""Warp set-up for :class:`~embodichain_core.sim.backend.warp_sim.WarpSim`: the kernel cache,
the device, and graphs of the step.

Warp compiles MuJoCo Warp's kernels on first use (about 30-50 s on a CPU) and keeps them
in a kernel cache. :func:`init_warp` points that cache at ``.warp_cache/`` of the project
checkout (ignored by git) unless ``EMBODICHAIN_WARP_CACHE`` names another folder (an
installed, non-editable package uses Warp's own default), so later runs load the
kernels in milliseconds.

:class:`StepGraphs` captures a function (the step, the refresh, the reset) into a graph
once and replays it: a CUDA graph on a GPU, Warp's recorded kernel launches on its CPU
device. A graph keeps the array pointers of its capture, so the backend calls
:meth:`StepGraphs.clear` whenever it replaces a model array (expanding a field per env) and
the next call captures again; a capture that fails falls back to direct launches (with a
warning). **The CUDA path is untested** (no GPU was lent to this task).

:func:`host_arrays_for` decides once, at build, whether the backend offers numpy views of
its state (``capabilities.host_arrays``): on Warp's CPU device by default, never on a GPU.
Inside :func:`cpu_device_route` a sim on Warp's CPU device is built without them, so the
env takes the code paths a GPU runs (what
:class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit` measures).
"""

from __future__ import annotations

import contextlib
import os
import warnings
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Callable, Iterator, Optional

import torch

from embodichain_core.config.errors import ConfigError

#: Environment variable naming the Warp kernel cache folder.
CACHE_ENV = "EMBODICHAIN_WARP_CACHE"
_CPU_DEVICE_ROUTE: ContextVar[bool] = ContextVar("embodichain_cpu_device_route", default=False)


@contextlib.contextmanager
def cpu_device_route() -> Iterator[None]:
    """Within the block, a ``WarpSim`` built on Warp's CPU device (with ``host_arrays`` left
    at its default) has no numpy views of its state: ``capabilities.host_arrays`` is False,
    ``sim.arrays`` is absent, and entities and the env's robot commands take the torch
    views, as on a GPU. The env runs the GPU's code paths on the CPU, so that a test (the
    device audit, a comparison with the host route) can exercise them without a GPU.
    """
    was = _CPU_DEVICE_ROUTE.get()
    _CPU_DEVICE_ROUTE.set(True)
    try:
        yield
    finally:
        _CPU_DEVICE_ROUTE.set(was)


def host_arrays_for(wp_device: str, requested: Optional[bool] = None) -> bool:
    """Whether a sim on ``wp_device`` offers numpy views of its state.

    Args:
        wp_device: Warp's device name (``"cpu"``, ``"cuda:0"``).
        requested: ``None``: on the CPU unless inside :func:`cpu_device_route`; ``False``:
            never; ``True``: on the CPU only.

    Raises:
        ValueError: ``requested`` is True on a GPU (no numpy view of device memory exists).
    """
    on_cpu = wp_device == "cpu"
    if requested is None:
        return on_cpu and not _CPU_DEVICE_ROUTE.get()
    if requested and not on_cpu:
        raise ValueError(f"WarpSim(host_arrays=True): device {wp_device!r} has no host views of its memory")
    return bool(requested)


def default_cache_dir() -> Optional[Path]:
    """``.warp_cache/`` at the project checkout's root (``None`` outside a checkout)."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    root = Path(__file__).resolve().parents[3]
    if (root / "pyproject.toml").is_file() and (root / "embodichain_core").is_dir():
        return root / ".warp_cache"
    return None


def init_warp() -> Any:
    """Import and initialize Warp once (kernel cache of :func:`default_cache_dir`, quiet).

    Returns:
        The ``warp`` module.

    Raises:
        ConfigError: at ``sim_cfg.backend`` when ``mujoco-warp`` is not installed.
    """
    try:
        import warp as wp
        import mujoco_warp  # noqa: F401
    except ImportError as err:
        raise ConfigError(
            "sim_cfg.backend",
            "backend 'warp' needs MuJoCo Warp: pip install "
            "'embodichain-core[warp]' (mujoco-warp, warp-lang); or use backend "
            f"'mujoco_batch' ({err})",
        ) from err
    if wp.config.kernel_cache_dir is None:  # not initialized yet (init sets the default)
        cache = default_cache_dir()
        if cache is not None:
            wp.config.kernel_cache_dir = str(cache)
        wp.config.log_level = wp.LOG_WARNING  # no banner, no line per loaded module
    wp.init()
    return wp


def resolve_device(wp: Any, sim_device: str) -> str:
    """The Warp device of ``sim_cfg.sim_device`` (``cpu``, ``cuda``, ``cuda:N``).

    Raises:
        ConfigError: at ``sim_cfg.sim_device`` for another name, or CUDA without a GPU.
    """
    name = str(sim_device or "cpu").strip().lower()
    if name == "cpu":
        return "cpu"
    if name == "cuda" or (name.startswith("cuda:") and name[5:].isdigit()):
        if not wp.is_cuda_available():
            raise ConfigError(
                "sim_cfg.sim_device",
                f"{sim_device!r}: Warp finds no CUDA device here; "
                "use 'cpu' (Warp's CPU device, slow but exact enough for testing)",
            )
        return "cuda:0" if name == "cuda" else name
    raise ConfigError(
        "sim_cfg.sim_device", f"{sim_device!r} is not a device of backend 'warp'; use 'cpu', 'cuda' or 'cuda:N'"
    )


def torch_device(device: str) -> torch.device:
    """The torch device sharing memory with Warp device ``device``."""
    return torch.device("cpu") if device == "cpu" else torch.device(device)


class StepGraphs:
    """Captured graphs of parameterless functions, keyed by name.

    Args:
        wp: the ``warp`` module.
        device: the Warp device.
    """

    def __init__(self, wp: Any, device: str):
        self._wp = wp
        self.device = device
        self._graphs: dict[Any, Any] = {}
        # Warp records CPU launches too: a replay skips the Python cost of ~100 kernel launches
        # per MuJoCo step (docs/performance.md, section 4); CUDA capture needs a memory pool
        self.enabled = device == "cpu" or bool(wp.is_mempool_enabled(device))

    def clear(self) -> None:
        """Forget every graph (after a model array was replaced)."""
        self._graphs.clear()

    def run(self, key: Any, fn: Callable[[], None]) -> None:
        """Run ``fn`` once: replay its graph, capturing it first when CUDA graphs are
        enabled (Warp loads the modules a capture needs; the capture itself runs nothing)."""
        wp = self._wp
        if not self.enabled:
            with wp.ScopedDevice(self.device):
                fn()
            return
        graph = self._graphs.get(key)
        if graph is None:
            try:
                with wp.ScopedDevice(self.device), wp.ScopedCapture(device=self.device) as capture:
                    fn()
            except Exception as err:  # a capture runs nothing: fall back to direct calls, once
                warnings.warn(
                    f"Warp graph capture failed on {self.device} ({err}); the warp backend "
                    "launches its kernels directly from now on",
                    RuntimeWarning,
                    stacklevel=3,
                )
                self.enabled = False
                self.run(key, fn)
                return
            graph = self._graphs[key] = capture.graph
        wp.capture_launch(graph)
