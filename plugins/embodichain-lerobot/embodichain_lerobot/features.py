"""LeRobot features of an env's observations and actions.

The observation (flattened with ``/``) maps to features as follows:

=====================================  ==============================================  ==========
observation key                        feature                                         stored as
=====================================  ==============================================  ==========
``robot/qpos``, ``qvel``, ``qf``       ``observation.state``, ``.qvel``, ``.qf``       float32, named by joint
``robot/<x>`` (observation functors)   ``observation.robot.<x>``                       numeric
``sensor/<cam>/color[_right]``         ``observation.images.<cam>[_right]``            image/video (H, W, 3)
``sensor/<cam>/depth[_right]``         ``observation.depth.<cam>[_right]``             lossless video/PNG, 16-bit mm
``sensor/<cam>/mask[_right]``          ``observation.mask.<cam>[_right]``              lossless video/PNG, 16-bit id+1
``sensor/<cam>/<other>``               skipped with a warning (normal, position, ...)
``sensor/<contact>/<field>``           ``<contact>.<field>``                           numeric
``<key>`` (top-level tensor)           ``<key>``                                       numeric
``<a>/<b>`` (nested extra)             ``observation.<a>.<b>``                         numeric
=====================================  ==============================================  ==========

Depth and masks pack 16-bit values into RGB (:mod:`embodichain_lerobot.packing`:
millimetres, and entity id + 1), stored as lossless video features with the
recorder's ``depth_format: "video"`` (:mod:`embodichain_lerobot.lossless_video`) or
as lossless PNG image features with ``"png16"``; with ``"raw"`` they stay numeric features of the sensor's
dtype (float32 metres, int32 ids). Scalar shapes ``()`` become ``(1,)``. The action is ``action["qpos"]`` when the
action is a mapping with that key, else its first tensor (or the tensor itself).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Iterator, Optional, Sequence

import numpy as np
import torch

from embodichain_core.config.errors import ConfigError
from embodichain_lerobot.env_state import state_source
from embodichain_lerobot.packing import pack_depth, pack_mask

ROBOT_KEYS = {"robot/qpos": "observation.state", "robot/qvel": "observation.qvel", "robot/qf": "observation.qf"}
ANNOTATIONS = ("episode_step", "segment_id", "segment_step", "segment_start", "segment_end", "terminated", "truncated")
#: Per-frame fields every recorded dataset has besides the observations and the action.
FIXED_FEATURES: dict[str, dict] = {
    "next.reward": {"dtype": "float32", "shape": (1,), "names": None},
    "next.done": {"dtype": "bool", "shape": (1,), "names": None},
    "next.success": {"dtype": "bool", "shape": (1,), "names": None},
    "subtask_index": {"dtype": "int64", "shape": (1,), "names": None},
    **{f"annotation.{a}": {"dtype": "int64", "shape": (1,), "names": None} for a in ANNOTATIONS},
}
RESERVED = {"timestamp", "frame_index", "episode_index", "index", "task_index", "task", "action", *FIXED_FEATURES}
_CAMERA_STREAMS = {"color": "images", "depth": "depth", "mask": "mask"}
#: Source kinds stored as lerobot image (or video) features.
IMAGE_KINDS = ("image", "depth", "mask")


def flatten_obs(obs: Any, prefix: str = "") -> dict[str, Any]:
    """``{"robot": {"qpos": t}}`` -> ``{"robot/qpos": t}`` (dicts and TensorDicts)."""
    if hasattr(obs, "items") and not isinstance(obs, torch.Tensor):
        out: dict[str, Any] = {}
        for key, value in obs.items():
            out.update(flatten_obs(value, f"{prefix}/{key}" if prefix else str(key)))
        return out
    return {prefix: obs}


def to_numpy(value: Any) -> np.ndarray:
    """A tensor/array as a numpy array on the CPU (no copy when possible)."""
    if isinstance(value, torch.Tensor):
        return value.detach().cpu().numpy()
    return np.asarray(value)


@dataclass
class Source:
    """One recorded observation stream: where it comes from and how it is stored."""

    key: str
    name: str
    kind: str  # "numeric", "image" (colour), "depth" or "mask" (packed 16-bit values)
    dtype: str
    shape: tuple
    names: Optional[list] = None
    lossless_video: bool = False  # depth/mask stored as a lossless video (depth_format "video")

    def take(self, flat: dict[str, Any], num_envs: int) -> np.ndarray:
        """This stream's batch of a flattened observation (see :meth:`convert`)."""
        return self.convert(flat[self.key], num_envs)

    def convert(self, value: Any, num_envs: int) -> np.ndarray:
        """The batch ``(N, ...)`` as an owned array of the feature dtype and shape."""
        fresh = isinstance(value, torch.Tensor) and value.device.type != "cpu"  # .cpu() copies it off the GPU
        arr = to_numpy(value)
        if self.kind == "image":
            return _rgb(arr, owned=fresh)
        if self.kind == "depth":
            return pack_depth(arr)
        if self.kind == "mask":
            return pack_mask(arr)
        return np.array(arr, dtype=self.dtype, copy=True).reshape((num_envs,) + self.shape)

    def feature(self, use_videos: bool) -> dict:
        """The lerobot feature dict (depth and masks: lossless videos or PNG images)."""
        if self.kind in IMAGE_KINDS:
            video = use_videos and (self.kind == "image" or self.lossless_video)
            return {
                "dtype": "video" if video else "image",
                "shape": self.shape,
                "names": ["height", "width", "channels"],
            }
        return {"dtype": self.dtype, "shape": self.shape, "names": self.names}


def _rgb(arr: np.ndarray, owned: bool = False) -> np.ndarray:
    """``(N, H, W, C)`` colour as owned uint8 RGB (alpha dropped, grey repeated).

    uint8 RGBA (what cameras give) is copied whole, a plain memory copy, and the alpha
    dropped as a view of that copy: the 4-to-3 channel gather costs ~40x the copy, and
    it then happens once, off the stepping loop, where the frame is encoded. ``owned``:
    ``arr`` is already a fresh copy nothing else holds (a GPU's frames copied to the host),
    so the alpha is dropped as a view of it, without a second copy.
    """
    if arr.dtype == np.uint8 and arr.ndim == 4 and arr.shape[-1] == 4:
        return (arr if owned else np.array(arr, copy=True))[..., :3]
    if arr.ndim == 3:
        arr = arr[..., None]
    if np.issubdtype(arr.dtype, np.floating):
        arr = np.clip(arr, 0.0, 1.0) * 255.0 + 0.5
    rgb = arr[..., :3] if arr.shape[-1] >= 3 else np.repeat(arr[..., :1], 3, axis=-1)
    return np.array(rgb, dtype=np.uint8, copy=True)


def _numeric(key: str, name: str, value: Any, names: Optional[list] = None) -> Source:
    arr = to_numpy(value)
    shape = tuple(int(s) for s in arr.shape[1:]) or (1,)
    if names is not None and shape != (len(names),):
        names = None
    return Source(key, name, "numeric", str(arr.dtype), shape, names)


def _camera_source(key: str, uid: str, stream: str, value: Any, depth_format: str = "png16") -> Optional[Source]:
    base, _, side = stream.partition("_")
    group = _CAMERA_STREAMS.get(base)
    if group is None or side not in ("", "right"):
        warnings.warn(
            f"LeRobot recorder: camera stream {key!r} is not recorded (only colour, depth and mask are)",
            RuntimeWarning,
            stacklevel=4,
        )
        return None
    name = f"observation.{group}.{uid}" + ("_right" if side else "")
    if group != "images" and depth_format == "raw":
        return _numeric(key, name, value)
    shape = tuple(int(s) for s in to_numpy(value).shape[1:3]) + (3,)
    kind = {"images": "image"}.get(group, group)
    return Source(key, name, kind, "uint8", shape, None, lossless_video=kind != "image" and depth_format == "video")


def _is_camera(env: Any, uid: str, fields: list[str]) -> bool:
    sensor = (getattr(env, "sensors", None) or {}).get(uid)
    cfg = getattr(sensor, "cfg", None)
    if cfg is not None and hasattr(cfg, "width") and hasattr(cfg, "height"):
        return True
    return sensor is None and any(f.split("_")[0] == "color" for f in fields)


def _sources(flat: dict[str, Any], env: Any, joint_names: list[str], depth_format: str = "png16") -> Iterator[Source]:
    sensors: dict[str, list[str]] = {}
    for key in flat:
        parts = key.split("/")
        if parts[0] == "sensor" and len(parts) >= 3:
            sensors.setdefault(parts[1], []).append("/".join(parts[2:]))
    for key, value in flat.items():
        parts = key.split("/")
        if key in ROBOT_KEYS:
            yield _numeric(key, ROBOT_KEYS[key], value, list(joint_names))
        elif parts[0] == "sensor" and len(parts) >= 3:
            uid, stream = parts[1], "/".join(parts[2:])
            if _is_camera(env, uid, sensors[uid]):
                source = _camera_source(key, uid, stream, value, depth_format)
                if source is not None:
                    yield source
            else:
                yield _numeric(key, f"{uid}." + stream.replace("/", "."), value)
        elif len(parts) == 1:
            yield _numeric(key, key, value)
        else:
            yield _numeric(key, "observation." + ".".join(parts), value)


class FeatureSpec:
    """The recorded features of one env, fixed by its first observation and action.

    Args:
        obs: a batched observation of the env (``(N, ...)`` tensors).
        env: the env (joint names, sensors).
        depth_format: ``"video"`` (depth and masks as packed 16-bit lossless videos),
            ``"png16"`` (as packed 16-bit PNG images) or ``"raw"``.
        environment_state: observation keys recorded together as
            ``observation.environment_state`` (:mod:`embodichain_lerobot.env_state`).
    """

    def __init__(self, obs: Any, env: Any, depth_format: str = "png16", environment_state: Sequence[str] = ()):
        self.num_envs = int(env.num_envs)
        robot = env.robot
        self.joint_names = [str(robot.joint_names[j]) for j in env.active_joint_ids]
        sources = list(_sources(flatten_obs(obs), env, self.joint_names, depth_format))
        self.sources: list[Any] = state_source(sources, environment_state)[0]
        self._check_names()
        self.action_dim: Optional[int] = None
        manager = getattr(env, "action_manager", None)
        #: the policy action's names when the env has action terms (e.g. a TCP pose), else the joints'
        self.action_names = manager.action_names() if manager is not None and manager.terms("pre") else None

    def _check_names(self) -> None:
        seen: dict[str, str] = {}
        for s in self.sources:
            if s.name in RESERVED or s.name in seen:
                other = seen.get(s.name, "a built-in feature")
                raise ConfigError(
                    "observations",
                    f"observation {s.key!r} would be recorded as {s.name!r}, "
                    f"which is already used by {other}; rename the observation",
                )
            seen[s.name] = repr(s.key)

    def set_action(self, action: np.ndarray) -> None:
        """Fix the action dimension from the first recorded action ``(N, A)``."""
        if self.action_dim is None:
            self.action_dim = int(action.shape[1])

    def features(self, use_videos: bool) -> dict[str, dict]:
        """The lerobot ``features`` dict (without lerobot's default features)."""
        if self.action_dim is None:
            raise RuntimeError("no action recorded yet")
        names = self.action_names or self.joint_names
        names = names if self.action_dim == len(names) else None
        out = {s.name: s.feature(use_videos) for s in self.sources}
        out["action"] = {"dtype": "float32", "shape": (self.action_dim,), "names": names}
        out.update({k: dict(v) for k, v in FIXED_FEATURES.items()})
        return out

    def image_features(self, use_videos: bool) -> list[str]:
        """The names of the features stored as PNG images (not videos)."""
        return [s.name for s in self.sources if s.kind in IMAGE_KINDS and s.feature(use_videos)["dtype"] == "image"]

    def lossless_videos(self, use_videos: bool) -> list[str]:
        """The names of the features stored as lossless videos (depth and masks)."""
        return [s.name for s in self.sources if s.lossless_video and s.feature(use_videos)["dtype"] == "video"]

    def snapshot(self, obs: Any) -> dict[str, np.ndarray]:
        """Owned numpy copies ``(N, ...)`` of the recorded observation streams."""
        flat = flatten_obs(obs)
        return {s.name: s.take(flat, self.num_envs) for s in self.sources}


def action_array(action: Any, num_envs: int) -> np.ndarray:
    """The recorded action ``(N, A)`` float32 of a step's raw action."""
    if hasattr(action, "items") and not isinstance(action, torch.Tensor):
        items = dict(action.items())
        action = items["qpos"] if "qpos" in items else next(iter(items.values()))
    arr = np.array(to_numpy(action), dtype=np.float32, copy=True)
    if arr.ndim <= 1:
        arr = np.broadcast_to(arr.reshape(1, -1), (num_envs, max(arr.size, 1))).copy()
    return arr.reshape(num_envs, -1)
