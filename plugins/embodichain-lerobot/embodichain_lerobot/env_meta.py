"""What a recorded dataset needs to rebuild its env: ``meta/embodichain_env.json``.

The recorder writes this file into the dataset folder when it reserves it, before the
first episode is published. lerobot ignores it (its loaders read ``meta/info.json``,
``meta/stats.json``, ``meta/tasks.parquet`` and ``meta/episodes/``), and
``embodichain generate`` copies it into a merged dataset. It holds:

- ``task_id`` and ``task_provider`` (the plugin that registers the task),
- ``cfg_class`` (``module:QualName`` of the env config class) and ``env_cfg``: the env's
  resolved config (every field, after the config file and the CLI overrides), as
  ``EmbodiedEnvCfg.to_dict()`` writes it,
- ``backend`` (``sim_cfg.backend``), ``num_envs``, ``control_frequency``,
- ``versions``: Python, embodichain-core, the task's plugin, mujoco, numpy, torch,
  lerobot (what decides whether a replay can be exact).

Each episode's seed is in ``meta/embodichain_episodes.jsonl`` (``episode_seed``).
:func:`build_env` rebuilds the env from the file (any number of envs, recording off),
which is what ``embodichain dataset replay`` uses.

Example:
    >>> meta = read_env_meta("outputs/datasets/dexforcew1_tabletop_pick_fork_000")  # doctest: +SKIP
    >>> env = build_env(meta, num_envs=1)  # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
import platform
import warnings
from importlib import metadata
from pathlib import Path
from typing import Any, Optional, Sequence

from embodichain_core.plugins.registry import import_target

__all__ = [
    "ENV_META",
    "build_env",
    "describe_env",
    "merge_env_meta",
    "read_env_meta",
    "version_mismatches",
    "write_env_meta",
]

#: The file, relative to the dataset folder.
ENV_META = "meta/embodichain_env.json"
SCHEMA_VERSION = 1
#: Distributions whose versions decide whether a replay is exact (the task's plugin is added).
_DISTRIBUTIONS = ("embodichain-core", "mujoco", "numpy", "torch", "lerobot")


def _version(dist: str) -> Optional[str]:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def _task_provider(task_id: str) -> Optional[dict[str, Any]]:
    """``{"plugin", "version"}`` of the plugin that registers ``task_id`` (``None``: not a plugin task)."""
    from embodichain_core.plugins import list_plugins, task_registry

    try:
        entry = task_registry().find(task_id)
    except Exception:  # an ambiguous id: the env was built, so gym knows it; no provider to name
        entry = None
    if entry is None:
        return None
    versions = {info.name: info.version for info in list_plugins()}
    return {"plugin": entry.provider, "version": versions.get(entry.provider) or _version(entry.provider)}


def current_versions(provider: Optional[dict[str, Any]] = None) -> dict[str, Optional[str]]:
    """The versions this process runs with (the task's plugin too, when given)."""
    out: dict[str, Optional[str]] = {"python": platform.python_version()}
    out.update({dist: _version(dist) for dist in _DISTRIBUTIONS})
    if provider is not None:
        out[str(provider["plugin"])] = provider.get("version")
    return out


def describe_env(env: Any) -> dict[str, Any]:
    """The metadata of an (unwrapped, built) env, as :data:`ENV_META` holds it."""
    env = getattr(env, "unwrapped", env)
    spec = getattr(env, "spec", None)
    task_id = str(getattr(spec, "id", "") or "")
    cfg = env.cfg
    provider = _task_provider(task_id) if task_id else None
    return {
        "schema_version": SCHEMA_VERSION,
        "task_id": task_id,
        "task_provider": provider,
        "cfg_class": f"{type(cfg).__module__}:{type(cfg).__qualname__}",
        "env_cfg": cfg.to_dict(),
        "backend": str(cfg.sim_cfg.backend),
        "num_envs": int(env.num_envs),
        "control_frequency": float(env.control_frequency),
        "versions": current_versions(provider),
    }


def env_meta_text(env: Any) -> str:
    """The :data:`ENV_META` file's text for ``env`` (JSON)."""
    return json.dumps(describe_env(env), indent=1, default=str) + "\n"


def write_env_meta(root: str | os.PathLike, env: Any) -> Path:
    """Write :data:`ENV_META` of ``env`` into the dataset folder ``root`` (atomically)."""
    return write_env_meta_text(root, env_meta_text(env))


def write_env_meta_text(root: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (from :func:`env_meta_text`) as ``root``'s :data:`ENV_META` (atomically)."""
    path = Path(root) / ENV_META
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)
    return path


def read_env_meta(root: str | os.PathLike) -> dict[str, Any]:
    """The :data:`ENV_META` of the dataset at ``root``.

    Raises:
        FileNotFoundError: the dataset has no such file (recorded before datasets carried
            it, or merged by a tool that dropped it); the message says what is missing.
    """
    path = Path(root) / ENV_META
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} does not exist: the dataset does not say which env recorded it "
            "(datasets recorded by LeRobotRecorder carry it; record the data again to replay it)"
        )
    data = json.loads(path.read_text(encoding="utf-8"))
    for key in ("task_id", "cfg_class", "env_cfg"):
        if key not in data:
            raise ValueError(f"{path} has no {key!r}: not an embodichain env description")
    return data


def merge_env_meta(shards: Sequence[str | os.PathLike], output: str | os.PathLike) -> Optional[Path]:
    """Give a dataset merged from ``shards`` their :data:`ENV_META` (``embodichain generate``).

    The shards of one run are built from one config; their files differ only in the
    recorder's ``save_path``. The first shard's file is written, with ``merged_from``
    (the number of shards) added, and ``shard_versions`` (each shard's) when their
    versions differ (with a warning: the data is merged all the same).

    Raises:
        ValueError: the shards were recorded by different tasks or config classes (their
            episodes could not all be replayed from one description).

    Returns:
        The written file, or ``None`` when no shard has one (recorded before datasets carried it).
    """
    metas = [read_env_meta(root) for root in shards if (Path(root) / ENV_META).is_file()]
    if not metas:
        return None
    first = metas[0]
    extra: dict[str, Any] = {"merged_from": len(metas)}
    for other in metas[1:]:
        for key in ("task_id", "cfg_class"):
            if other.get(key) != first.get(key):
                raise ValueError(f"the shards disagree on {key}: {first.get(key)!r} and {other.get(key)!r}")
    versions = [m.get("versions") for m in metas]
    if any(v != versions[0] for v in versions):  # kept, and said: a replay warns about what differs
        extra["shard_versions"] = versions
        warnings.warn(f"the merged shards were recorded with different versions: {versions}", stacklevel=2)
    path = Path(output) / ENV_META
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({**first, **extra}, indent=1) + "\n", encoding="utf-8")
    return path


def version_mismatches(meta: dict[str, Any]) -> list[str]:
    """``"name: recorded X, running Y"`` for each version that differs from this process's."""
    recorded = meta.get("versions") or {}
    running = current_versions(meta.get("task_provider"))
    return [
        f"{name}: recorded {recorded.get(name)}, running {running.get(name)}"
        for name in sorted(set(recorded) | set(running))
        if recorded.get(name) != running.get(name)
    ]


def build_env(meta: dict[str, Any], num_envs: int = 1, **fields: Any) -> Any:
    """Rebuild the env of a dataset's :data:`ENV_META` with ``gymnasium.make`` (recording off).

    Args:
        meta: :func:`read_env_meta`'s dict.
        num_envs: parallel envs of the rebuilt env (any episode replays on any env slot).
        **fields: further cfg fields to set (e.g. ``max_episode_steps``).

    Returns:
        The env, as ``gymnasium.make`` returns it, headless, with its dataset section dropped.
    """
    import gymnasium as gym

    from embodichain_core.plugins import load_plugins

    load_plugins()
    plain = json.loads(json.dumps(meta["env_cfg"]))
    plain["dataset"] = {}
    plain["num_envs"] = num_envs
    plain.setdefault("sim_cfg", {})["num_envs"] = num_envs
    plain["sim_cfg"]["headless"] = True
    plain.update(fields)
    cls: Any = import_target(meta["cfg_class"])
    cfg = cls.from_dict(plain, "")
    task_id = meta["task_id"]
    if task_id not in gym.registry:
        raise ValueError(f"the dataset was recorded by task {task_id!r}, which no installed plugin registers")
    return gym.make(task_id, cfg=cfg)
