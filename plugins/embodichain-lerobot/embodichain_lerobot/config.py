"""Recorder parameters, the dataset fps and the dataset folder naming.

A dataset goes to ``<save_path>/<robot_type>_<scene_type>_<task_description>_<NNN>``:
the parts are lower-cased, spaces become ``_`` (other characters unsafe in a
folder name too), and ``NNN`` is one more than the highest existing number for
that prefix. The folder is created atomically (``mkdir`` without ``exist_ok``),
so two runs never write into the same dataset and nothing is overwritten.

Example:
    >>> dataset_prefix("Arm7", "Table Top", "Push the cube")
    'arm7_table_top_push_the_cube'
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional

from embodichain_core.config.errors import ConfigError
from embodichain_core.utils.suggest import did_you_mean
from embodichain_lerobot.env_state import check_state_keys
from embodichain_lerobot.storage import DEFAULT_MIN_FREE_MB

#: Environment variable naming the default dataset root (``save_path`` not given).
ENV_DATASET_ROOT = "EMBODICHAIN_DEFAULT_DATASET_ROOT"
#: Default dataset root when neither ``save_path`` nor the variable is set.
DEFAULT_DATASET_ROOT = "./outputs/datasets"
#: The task string of frames when ``instruction["lang"]`` is not given.
UNKNOWN_TASK = "unknown_task"
VIDEO_CODECS = ("libsvtav1", "h264", "hevc", "auto")
#: How depth and mask maps are stored (``params.depth_format``). ``video`` and ``png16``
#: pack depth in millimetres and mask ids + 1 as 16-bit values into RGB
#: (:mod:`embodichain_lerobot.packing`): ``video`` as lossless H.264 video features
#: (:mod:`embodichain_lerobot.lossless_video`; needs ``use_videos`` and
#: ``streaming_encoding``; about half the size of ``png16``), ``png16`` as lossless PNG
#: image features; ``raw`` keeps the float32/int32 arrays as numeric features (large:
#: every reader pays for them). Not given: ``video`` when videos are streamed, else ``png16``.
DEPTH_FORMATS = ("video", "png16", "raw")
#: The most ``params.encoder_processes`` accepts (each process holds an encoder per env it serves).
MAX_ENCODER_PROCESSES = 64

_UNSAFE = re.compile(r"[^a-z0-9_.\-]+")


@dataclass
class RecorderParams:
    """The validated ``params`` of a LeRobot recorder.

    Attributes:
        save_path: dataset root directory.
        robot_meta: robot metadata; ``robot_type`` names the robot in the dataset.
        instruction: task instruction; ``lang`` becomes every frame's task.
        extra: free metadata (``scene_type``, ``task_description`` name the folder)
            stored with every episode in ``meta/embodichain_episodes.jsonl``.
        use_videos: store camera colour as AV1/H.264 video instead of PNG images.
        vcodec: lerobot video codec (``libsvtav1``, ``h264``, ``hevc``, ``auto``: a hardware
            encoder only when one actually opens here, else ``libsvtav1``).
        streaming_encoding: encode videos while the episode's frames are added (lerobot's
            streaming encoder: no PNG round trip, stats from the frames in memory); ``False``
            writes PNG frames and encodes them at ``save_episode`` (lerobot's default path).
        encoder_threads: threads per video encoder (``None``: the codec decides).
        depth_format: ``video``, ``png16`` or ``raw``, see :data:`DEPTH_FORMATS`.
        image_writer_threads, image_writer_processes: lerobot's async PNG writer (``None``
            threads: 2 when the dataset has image features, PNG-stored depth/masks included).
        max_pending_episodes: async recorder queue bound (0: unbounded).
        writer_process: write the dataset in a child process
            (:mod:`embodichain_lerobot.writer_process`: lerobot is imported and runs there,
            off this process's GIL). ``None`` lets the recorder choose: ``True`` for
            ``AsyncLeRobotRecorder``, ``False`` for ``LeRobotRecorder``.
        min_free_mb: megabytes that must stay free on the dataset's filesystem: checked
            before the env is built and before each episode is saved (see
            :mod:`embodichain_lerobot.storage`).
        environment_state: observation keys recorded together as one flat
            ``observation.environment_state`` feature (:mod:`embodichain_lerobot.env_state`).
        encoder_processes: processes that encode the streamed videos (``"auto"`` or an int
            from 1 to :data:`MAX_ENCODER_PROCESSES`; :func:`encoder_process_count`). 1: the
            dataset writer process encodes them itself.
    """

    save_path: str = ""
    robot_meta: dict = field(default_factory=dict)
    instruction: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    use_videos: bool = False
    vcodec: str = "libsvtav1"
    streaming_encoding: bool = True
    encoder_threads: Optional[int] = None
    depth_format: str = "png16"  # parse_params: "video" when videos are streamed
    image_writer_threads: Optional[int] = None
    image_writer_processes: int = 0
    max_pending_episodes: int = 64
    min_free_mb: int = DEFAULT_MIN_FREE_MB
    writer_process: Optional[bool] = None
    environment_state: list[str] = field(default_factory=list)
    encoder_processes: int | str = "auto"

    @property
    def task(self) -> str:
        """The task string of every frame."""
        return str(self.instruction.get("lang") or UNKNOWN_TASK)


def _as_dict(value: Any, name: str) -> dict:
    if value is None:
        return {}
    if isinstance(value, str) and name == "instruction":
        return {"lang": value}
    if not isinstance(value, Mapping):
        raise ConfigError(name, f"must be a mapping, got {type(value).__name__}")
    return dict(value)


def _non_negative_int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ConfigError(name, f"must be an int >= 0, got {value!r}")
    return value


def parse_params(params: Mapping[str, Any]) -> RecorderParams:
    """Validate a recorder's ``params`` (unknown keys are rejected by the manager)."""
    p = RecorderParams()
    p.save_path = str(params.get("save_path") or os.environ.get(ENV_DATASET_ROOT) or DEFAULT_DATASET_ROOT)
    p.robot_meta = _as_dict(params.get("robot_meta"), "robot_meta")
    p.instruction = _as_dict(params.get("instruction"), "instruction")
    p.extra = _as_dict(params.get("extra"), "extra")
    p.environment_state = check_state_keys(params.get("environment_state"))
    p.use_videos = bool(params.get("use_videos", False))
    p.vcodec = str(params.get("vcodec", p.vcodec))
    if p.vcodec not in VIDEO_CODECS:
        raise ConfigError("vcodec", f"must be one of {VIDEO_CODECS}, got {p.vcodec!r}")
    p.streaming_encoding = params.get("streaming_encoding", True)
    if not isinstance(p.streaming_encoding, bool):
        raise ConfigError("streaming_encoding", f"must be true or false, got {p.streaming_encoding!r}")
    p.depth_format = _depth_format(params.get("depth_format"), p.use_videos and p.streaming_encoding)
    p.writer_process = params.get("writer_process")
    if p.writer_process is not None and not isinstance(p.writer_process, bool):
        raise ConfigError("writer_process", f"must be true, false or null, got {p.writer_process!r}")
    for name in ("encoder_threads", "image_writer_threads"):
        if params.get(name) is not None:
            setattr(p, name, _non_negative_int(params[name], name))
    for name in ("image_writer_processes", "max_pending_episodes", "min_free_mb"):
        setattr(p, name, _non_negative_int(params.get(name, getattr(p, name)), name))
    p.encoder_processes = _encoder_processes(params.get("encoder_processes", "auto"))
    return p


def _encoder_processes(value: Any) -> int | str:
    """The validated ``encoder_processes``: ``"auto"`` or an int from 1 to :data:`MAX_ENCODER_PROCESSES`."""
    if value == "auto" or (
        isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= MAX_ENCODER_PROCESSES
    ):
        return value
    raise ConfigError("encoder_processes", f"must be 'auto' or an int from 1 to {MAX_ENCODER_PROCESSES}, got {value!r}")


def encoder_process_count(setting: int | str, num_envs: int, cpu_count: Optional[int] = None) -> int:
    """How many processes encode the streamed videos of ``num_envs`` envs.

    ``"auto"``: one per two cores beyond the two that stepping/rendering and the dataset
    writer take, ``(cpu_count - 2) // 2``, at least 1: 1 (the writer encodes, as without
    the setting) up to 5 cores, 3 on 8 cores, 7 on 16. Never more than ``num_envs`` (an
    env's videos are encoded in one process), also for an explicit count.

    Example:
        >>> encoder_process_count("auto", num_envs=4, cpu_count=2), encoder_process_count("auto", 64, 16)
        (1, 7)
        >>> encoder_process_count(8, num_envs=2)
        2
    """
    if setting == "auto":
        cpus = cpu_count if cpu_count is not None else (os.cpu_count() or 1)
        wanted = max(1, (cpus - 2) // 2)
    else:
        wanted = int(setting)
    return max(1, min(wanted, num_envs))


def _depth_format(value: Any, streamed_videos: bool) -> str:
    """The validated ``depth_format`` (``None``: ``video`` when videos are streamed, else ``png16``)."""
    if value is None:
        return "video" if streamed_videos else "png16"
    if value not in DEPTH_FORMATS:
        raise ConfigError(
            "depth_format", f"must be one of {DEPTH_FORMATS}, got {value!r}." + did_you_mean(str(value), DEPTH_FORMATS)
        )
    if value == "video" and not streamed_videos:
        raise ConfigError(
            "depth_format",
            "'video' stores depth and masks as lossless videos, which needs use_videos: true and "
            "streaming_encoding: true; set them, or use depth_format 'png16'",
        )
    return str(value)


def dataset_fps(control_frequency: float) -> int:
    """The dataset fps: the env control frequency, which must be a whole number of Hz.

    Raises:
        ValueError: for a non-integer frequency (LeRobot timestamps are ``frame / fps``).
    """
    freq = float(control_frequency)
    fps = round(freq)
    if not math.isfinite(freq) or fps < 1 or abs(freq - fps) > 1e-6 * max(1.0, freq):
        raise ValueError(
            f"LeRobot datasets need an integer fps, but the env control frequency is {freq:.6g} Hz "
            "(1 / (physics_dt * sim_steps_per_control)); choose sim_steps_per_control or "
            "target_control_frequency so that it is a whole number of Hz"
        )
    return int(fps)


def slug(text: Any) -> str:
    """``text`` lower-cased with spaces (and unsafe characters) replaced by ``_``."""
    out = _UNSAFE.sub("_", str(text).strip().lower().replace(" ", "_")).strip("_.")
    return out or "unnamed"


def dataset_prefix(robot_type: Any, scene_type: Any, task_description: Any) -> str:
    """``<robot_type>_<scene_type>_<task_description>`` as a folder name prefix."""
    return "_".join(slug(part) for part in (robot_type, scene_type, task_description))


def naming_parts(params: RecorderParams, robot_uid: str) -> tuple[str, str, str]:
    """(robot_type, scene_type, task_description) with defaults for missing parts."""
    robot_type = params.robot_meta.get("robot_type") or robot_uid or "robot"
    scene_type = params.extra.get("scene_type") or "scene"
    task = params.extra.get("task_description") or params.instruction.get("lang") or "task"
    return str(robot_type), str(scene_type), str(task)


def reserve_dataset_dir(save_path: str | os.PathLike, prefix: str, max_tries: int = 1000) -> Path:
    """Create and return ``<save_path>/<prefix>_<NNN>`` with the next free number."""
    root = Path(save_path).expanduser()
    root.mkdir(parents=True, exist_ok=True)
    pattern = re.compile(re.escape(prefix) + r"_(\d{3,})$")
    taken = [int(m.group(1)) for p in root.iterdir() if (m := pattern.match(p.name))]
    number = max(taken) + 1 if taken else 0
    for _ in range(max_tries):
        path = root / f"{prefix}_{number:03d}"
        try:
            path.mkdir()
            return path
        except FileExistsError:  # another run took it meanwhile
            number += 1
    raise RuntimeError(f"could not reserve a dataset folder for {prefix!r} under {root}")


def robot_type_of(params: RecorderParams, robot_uid: str) -> Optional[str]:
    """The ``robot_type`` written into the dataset info."""
    return str(params.robot_meta.get("robot_type") or robot_uid or "") or None
