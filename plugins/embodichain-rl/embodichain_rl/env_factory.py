"""Build the batched env the adapters wrap: ``gym.make(task_id, num_envs=N)`` with an
optional episode limit and an optional camera for videos.

Example:
    >>> env = make_env("PushCube-v1", num_envs=8, seed=0)  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

__all__ = ["make_env", "env_cfg_class", "VIDEO_CAMERA"]

#: uid of the camera :func:`make_env` adds with ``video=True``.
VIDEO_CAMERA = "rl_video"


def env_cfg_class(task_id: str) -> type:
    """The config class (``cfg_cls``) of the env registered as ``task_id``."""
    import gymnasium as gym

    import embodichain_core  # noqa: F401  (loads the plugins: registers the task ids)

    try:
        spec = gym.spec(task_id)
    except gym.error.Error as err:
        raise ValueError(f"unknown task {task_id!r}: {err}") from None
    entry = spec.entry_point
    creator = gym.envs.registration.load_env_creator(entry) if isinstance(entry, str) else entry
    cfg_cls = getattr(creator, "cfg_cls", None)
    if cfg_cls is None:
        raise ValueError(f"task {task_id!r} ({entry!r}) is not an embodichain env (no cfg_cls)")
    return cfg_cls


def _video_camera(width: int, height: int) -> Any:
    from embodichain_sensors import CameraCfg

    focal = 0.9 * width
    return CameraCfg(
        uid=VIDEO_CAMERA,
        width=width,
        height=height,
        intrinsics=(focal, focal, width / 2, height / 2),
        extrinsics=CameraCfg.ExtrinsicsCfg(eye=(1.25, 0.75, 1.05), target=(0.45, 0.0, 0.42)),
    )


def make_env(
    task_id: str,
    num_envs: int,
    seed: int | None = 0,
    max_episode_steps: int = 0,
    video: bool = False,
    video_size: tuple[int, int] = (320, 240),
) -> Any:
    """The unwrapped batched env of ``task_id``.

    Args:
        task_id: a registered embodichain task (``"PushCube-v1"``).
        num_envs: envs simulated together.
        seed: the env seed (``None``: random).
        max_episode_steps: episode limit; ``0`` keeps the task's.
        video: add a ``(width, height) = video_size`` camera, ``obs["sensor"][VIDEO_CAMERA]``.
        video_size: size of that camera's images.

    Returns:
        The ``EmbodiedEnv`` (not wrapped by gymnasium).
    """
    import gymnasium as gym

    if num_envs < 1:
        raise ValueError(f"num_envs must be >= 1, got {num_envs}")
    kwargs: dict[str, Any] = {"num_envs": num_envs, "seed": seed, "verbose": False}
    if max_episode_steps > 0 or video:  # through the cfg: gym.make keeps a max_episode_steps kwarg for itself
        cfg = env_cfg_class(task_id)()
        if max_episode_steps > 0:
            cfg.max_episode_steps = max_episode_steps
        if video:
            cfg.sensor = [*cfg.sensor, _video_camera(*video_size)]
        kwargs["cfg"] = cfg
    else:
        env_cfg_class(task_id)  # a clear error for unknown or non-embodichain tasks
    return gym.make(task_id, **kwargs).unwrapped
