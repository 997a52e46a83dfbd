"""embodichain-lerobot: record embodichain-core episodes as LeRobot datasets.

The recorders are dataset functors (``func: "LeRobotRecorder"`` or
``"AsyncLeRobotRecorder"`` in a gym config's ``dataset`` section); the
``embodichain dataset info|preview`` commands inspect what they wrote. Importing
this package is cheap: lerobot is imported only once a recorder starts recording
(on a background thread, so building an env does not wait for it) or a command
that needs it runs.

Example:
    >>> cfg.dataset = {"lerobot": DatasetFunctorCfg(  # doctest: +SKIP
    ...     func="LeRobotRecorder",
    ...     params={"save_path": "outputs/datasets", "robot_meta": {"robot_type": "arm7"},
    ...             "instruction": {"lang": "push the cube"}, "extra": {"scene_type": "table"}})}
"""

from __future__ import annotations

from typing import Any

__all__ = ["LeRobotRecorder", "AsyncLeRobotRecorder", "__version__"]
__version__ = "0.1.0"

_LAZY = {
    "LeRobotRecorder": "embodichain_lerobot.recorder",
    "AsyncLeRobotRecorder": "embodichain_lerobot.async_recorder",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
