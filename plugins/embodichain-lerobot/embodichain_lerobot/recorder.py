"""``LeRobotRecorder``: a dataset functor that saves committed episodes with lerobot.

Each step's observation is copied once (numpy, CPU) into per-env buffers; the
env's dataset manager commits an env's episode when it ends successfully (every
finished episode with ``save_failed_episodes``) and discards it otherwise or on
``reset(options={"save_data": False})``. A committed episode is written with
``LeRobotDataset.add_frame`` / ``save_episode`` and published crash-safely (see
:mod:`embodichain_lerobot.writer`). ``finalize()`` (from ``env.close()``) drops
live partial episodes and returns the dataset folder.

The output folder is checked before the env is built (``run-env`` calls
:meth:`LeRobotRecorder.preflight`; the constructor checks again), folders of
earlier recordings that were killed before saving an episode are removed
(:func:`~embodichain_lerobot.folders.clean_incomplete`), free space is checked
before each save, and each episode's seed (``env.episode_seeds``, when the env has
it) goes into ``meta/embodichain_episodes.jsonl``.

Config (a gym config's ``dataset`` section)::

    "dataset": {"lerobot": {"func": "LeRobotRecorder", "params": {
        "save_path": "outputs/datasets", "robot_meta": {"robot_type": "arm7"},
        "instruction": {"lang": "push the cube"}, "extra": {"scene_type": "table"},
        "use_videos": false}}}
"""

from __future__ import annotations

import logging
import os
import shutil
from pathlib import Path
from typing import Any, Iterator, Mapping, Optional

import numpy as np

from embodichain_core.config.errors import ConfigError
from embodichain_core.managers.functor import DatasetFunctor
from embodichain_lerobot.config import (
    dataset_fps,
    dataset_prefix,
    naming_parts,
    parse_params,
    reserve_dataset_dir,
    robot_type_of,
)
from embodichain_lerobot.encoder_pool import EncoderPool, pool_for
from embodichain_lerobot.encoding import preload_lerobot
from embodichain_lerobot.env_meta import env_meta_text
from embodichain_lerobot.episodes import Episode, EpisodeBuffers, StepData
from embodichain_lerobot.features import FeatureSpec, action_array, to_numpy
from embodichain_lerobot.folders import clean_incomplete, folder_status
from embodichain_lerobot.storage import DEFAULT_MIN_FREE_MB, check_output_dir, ensure_space
from embodichain_lerobot.writer import DatasetWriter
from embodichain_lerobot.writer_process import WriterProcess

log = logging.getLogger("embodichain_lerobot")


def env_id_list(env_ids: Any, num_envs: int) -> list[int]:
    """``env_ids`` (tensor, list, ``None`` = all) as a list of ints."""
    if env_ids is None:
        return list(range(num_envs))
    return [int(i) for i in np.asarray(to_numpy(env_ids)).reshape(-1)]


def _per_env(value: Any, num_envs: int, dtype: Any) -> np.ndarray:
    if value is None:
        return np.zeros(num_envs, dtype=dtype)
    arr = np.asarray(to_numpy(value), dtype=dtype).reshape(-1)
    return np.broadcast_to(arr, (num_envs,)).copy() if arr.size == 1 else arr.copy()


class LeRobotRecorder(DatasetFunctor):
    """Records the env's committed episodes as a LeRobot dataset.

    Params (read at construction; see :class:`~embodichain_lerobot.config.RecorderParams`):
    ``save_path``, ``robot_meta``, ``instruction``, ``extra``, ``use_videos``,
    ``vcodec``, ``streaming_encoding``, ``encoder_threads``, ``depth_format``,
    ``image_writer_threads``, ``image_writer_processes``, ``max_pending_episodes``
    (async variant only), ``min_free_mb``, ``writer_process`` (write in a child process;
    default off here, on in the async variant), ``environment_state`` (observation keys
    recorded as one ``observation.environment_state`` vector), ``encoder_processes``
    (streamed videos encoded by that many processes beside the writer process,
    :mod:`embodichain_lerobot.encoder_pool`). lerobot is imported on a thread once the
    first observation is recorded (the env build does not wait for it); with ``writer_process`` it is
    imported in the child, which starts with the first recorded observation (a recorder closed
    before its env is reset starts none).

    Raises:
        ValueError: the env control frequency is not a whole number of Hz.
        ConfigError: ``save_path`` is not writable or its filesystem has less than ``min_free_mb`` free.
    """

    #: ``params.writer_process`` when the config leaves it out.
    default_writer_process = False

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        try:
            self.params = parse_params(cfg.params or {})
        except ConfigError as err:  # named as in the config (the env build adds the functor's path)
            raise err.under("params") from None
        self.fps = dataset_fps(env.control_frequency)
        check_output_dir(self.params.save_path, self.params.min_free_mb, "params.save_path")
        if self.params.use_videos:
            os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 prints its banner at every encoder start otherwise
        self.step_dt = float(env.step_dt)
        self._robot_uid = str(getattr(env.robot, "uid", "") or "")
        clean_incomplete(self.params.save_path, dataset_prefix(*naming_parts(self.params, self._robot_uid)))
        self._spec: Optional[FeatureSpec] = None
        self._buffers = EpisodeBuffers(env.num_envs)
        self._writer: Optional[DatasetWriter | WriterProcess] = None
        if self.params.writer_process is None:
            self.params.writer_process = self.default_writer_process
        # its child starts with the first recorded observation (_ensure_spec): a recorder never reset starts none
        self._writer_process = WriterProcess() if self.params.writer_process else None
        # params.encoder_processes > 1: the streamed videos are encoded there, the writer takes them
        self._encoders: Optional[EncoderPool] = pool_for(self.params, env.num_envs)
        self._finalized = False
        self._path: Optional[str] = None
        self.discarded_episodes = 0

    @classmethod
    def preflight(cls, params: Mapping[str, Any], path: str) -> None:
        """Check the params and the output folder before the env is built (``run-env`` calls it).

        Args:
            params: the functor's ``params``.
            path: the functor's config path (``env.dataset.lerobot``), for the errors.

        Raises:
            ConfigError: a bad param, or an unusable ``save_path`` (named by its config key).
        """
        try:
            p = parse_params(params or {})
        except ConfigError as err:
            raise err.under(f"{path}.params") from None
        check_output_dir(p.save_path, p.min_free_mb, f"{path}.params.save_path")

    # -- status ----------------------------------------------------------------------------------
    @property
    def dataset_path(self) -> Optional[Path]:
        """The dataset folder (``None`` until the first episode is committed)."""
        return self._writer.root if self._writer is not None else None

    @property
    def saved_episodes(self) -> int:
        """Episodes saved so far, as the dataset's ``meta/info.json`` counts them (what loads,
        whatever happened to the writer); the writer's own count before that file exists."""
        if self._writer is None:
            return 0
        status = folder_status(self._writer.root)
        return status.episodes if status.readable and status.episodes else self._writer.num_episodes

    @property
    def lost_episodes(self) -> int:
        """Finished episodes handed to a writer process that died before writing them."""
        return len(self._writer_process.lost_episodes) if self._writer_process is not None else 0

    @property
    def saved_frames(self) -> int:
        return self._writer.num_frames if self._writer is not None else 0

    def live_length(self, env_id: int) -> int:
        """Frames buffered for env ``env_id``'s live episode."""
        return self._buffers.length(env_id)

    # -- recording -------------------------------------------------------------------------------
    def _ensure_spec(self, obs: Any) -> FeatureSpec:
        if self._spec is None:
            self._spec = FeatureSpec(obs, self._env, self.params.depth_format, self.params.environment_state)
            if self._writer_process is None:
                preload_lerobot()  # lerobot takes seconds to import: on a thread, after the env is built
            else:  # the child imports lerobot while the first episodes run
                self._writer_process.start()
                if self._encoders is not None:
                    self._encoders.start()
        return self._spec

    def record_reset(self, obs: Any, env_ids: Any) -> None:
        """New episodes of ``env_ids`` start from ``obs``."""
        if self._finalized:
            return
        spec, ids = self._ensure_spec(obs), env_id_list(env_ids, self.num_envs)
        self._buffers.start(spec.snapshot(obs), ids)
        self._restart(ids)

    def record_step(self, obs: Any, action: Any, reward: Any, terminated: Any, truncated: Any, info: dict) -> None:
        """Buffer one frame per env (the observation it acted on, the action, reward, flags)."""
        if self._finalized:
            return
        spec, n = self._ensure_spec(obs), self.num_envs
        act = action_array(action, n)
        spec.set_action(act)
        step = StepData(
            act,
            _per_env(reward, n, np.float32),
            _per_env(terminated, n, bool),
            _per_env(truncated, n, bool),
            _per_env((info or {}).get("success"), n, bool),
        )
        proc = self._streaming_to()
        if proc is not None:
            self._ensure_writer()  # opened at the first step: the frames go out from then on
            target = self._encoders if self._encoders is not None else proc  # encoded there
            for snapshot, ids in self._buffers.pending_groups() if proc.streamed else ():
                target.stream_frames(snapshot, ids)  # the frames this step completes
        self._buffers.add(spec.snapshot(obs), step)

    def _streaming_to(self) -> Optional[WriterProcess]:
        """The writer process when video frames go to it while the episodes run, else ``None``."""
        p = self.params
        return self._writer_process if p.use_videos and p.streaming_encoding else None

    def _restart(self, env_ids: list[int]) -> None:
        """The live episodes of ``env_ids`` ended without a commit (their encoding is cancelled)."""
        if self._encoders is not None:
            self._encoders.restart(env_ids)
        elif self._writer_process is not None:
            self._writer_process.restart(env_ids)

    def __call__(
        self,
        env: Any,
        env_ids: Any,
        save_path: Any = None,
        robot_meta: Any = None,
        instruction: Any = None,
        extra: Any = None,
        use_videos: bool = False,
        vcodec: str = "libsvtav1",
        image_writer_threads: Optional[int] = None,
        image_writer_processes: int = 0,
        max_pending_episodes: int = 64,
        min_free_mb: int = DEFAULT_MIN_FREE_MB,
        streaming_encoding: bool = True,
        encoder_threads: Optional[int] = None,
        depth_format: Optional[str] = None,
        writer_process: Optional[bool] = None,
        environment_state: Optional[list] = None,
        encoder_processes: int | str = "auto",
    ) -> None:
        """Commit the finished episodes of ``env_ids`` (the params were read at construction).

        Each episode keeps its seed, ``env.episode_seeds[i]`` now (before the next episode draws its seed).
        """
        if self._finalized:
            raise RuntimeError(f"{type(self).__name__} is finalized; it accepts no more episodes")
        seeds = getattr(env, "episode_seeds", None)
        for i in env_id_list(env_ids, self.num_envs):
            episode = self._buffers.take(i)
            if len(episode):  # zero-length episodes (the first reset) are skipped
                episode.seed = int(seeds[i]) if seeds is not None else None
                self._write(episode)

    def discard(self, env_ids: Any) -> None:
        """Drop the live episodes of ``env_ids``."""
        ids = env_id_list(env_ids, self.num_envs)
        for i in ids:
            self.discarded_episodes += int(self._buffers.drop([i]) > 0)
        self._restart(ids)

    def reset(self, env_ids: Any = None) -> None:
        """After a reset nothing is left of the old episodes of ``env_ids``."""
        ids = env_id_list(env_ids, self.num_envs)
        self._buffers.drop(ids)
        self._restart(ids)

    # -- writing ---------------------------------------------------------------------------------
    def _write(self, episode: Episode) -> None:
        """Write a committed episode (the async recorder queues it instead)."""
        self._write_now(episode)

    def _prepare(self, episode: Episode) -> tuple[DatasetWriter | WriterProcess, Iterator[dict], dict]:
        """Check the free space, then the writer, the frames and the record of ``episode``."""
        where = self._writer.root if self._writer is not None else self.params.save_path
        try:
            ensure_space(
                where,
                episode.nbytes(),
                self.params.min_free_mb,
                f"episode {self.saved_episodes} (env {episode.env_id}, {len(episode)} frames) to {where}",
            )
        except BaseException:
            self._restart([episode.env_id])  # its streamed videos are not kept for the next episode
            raise
        writer, task = self._ensure_writer(), self.params.task
        subtask = writer.subtask_index(task)
        return writer, episode.frames(task, subtask), self._episode_record(episode, subtask)

    def _write_now(self, episode: Episode) -> None:
        writer, frames, record = self._prepare(episode)
        index = writer.write_episode(frames, record, **self._episode_videos(episode.env_id))
        log.info("saved episode %d of env %d (%d frames) to %s", index, episode.env_id, len(episode), writer.root)

    def _episode_videos(self, env_id: int) -> dict[str, Any]:
        """``write_episode``'s arguments naming the encoder process that finishes the committed
        episode's videos (none without encoder processes)."""
        if self._encoders is None:
            return {}
        ticket, sent = self._encoders.finish(env_id)
        return {"ticket": ticket, "after": sent}

    def _ensure_writer(self) -> DatasetWriter | WriterProcess:
        if self._writer is not None:
            return self._writer
        if self._spec is None or self._spec.action_dim is None:
            raise RuntimeError("no frame was recorded before the first commit")
        p = self.params
        root = reserve_dataset_dir(p.save_path, dataset_prefix(*naming_parts(p, self._robot_uid)))
        threads = p.image_writer_threads
        if threads is None:  # PNG features (depth, masks, colour without videos): write them on threads
            threads = 2 if self._spec.image_features(p.use_videos) else 0
        args = (self.fps, self._spec.features(p.use_videos), robot_type_of(p, self._robot_uid), p.use_videos)
        more = (p.vcodec, threads, p.image_writer_processes)
        kwargs: dict[str, Any] = {
            "streaming_encoding": p.streaming_encoding,
            "encoder_threads": p.encoder_threads,
            "lossless_keys": self._spec.lossless_videos(p.use_videos),
            "env_meta": env_meta_text(self._env),  # written by the writer, under its recording marker
        }
        try:
            if self._writer_process is not None:  # not waited for: an error comes with the first episode
                streamed = [k for k, f in args[1].items() if f["dtype"] == "video"] if self._streaming_to() else []
                remote = None
                if self._encoders is not None:  # they encode the streamed videos; the writer takes them
                    settings = (self.fps, p.vcodec, p.encoder_threads, streamed, kwargs["lossless_keys"])
                    remote = self._encoders.open(root, *settings)
                self._writer_process.open(root, *args, *more, streamed=streamed, remote=remote, **kwargs)
                self._writer = self._writer_process
            else:
                self._writer = DatasetWriter(root, *args, *more, **kwargs)
        except BaseException:
            shutil.rmtree(root, ignore_errors=True)
            raise
        return self._writer

    def _episode_record(self, episode: Episode, subtask: int) -> dict:
        task, n = self.params.task, len(episode)
        return {
            "env_id": episode.env_id,
            "success": episode.success,
            "total_time": n * self.step_dt,
            "instruction": self.params.instruction,
            "robot_meta": self.params.robot_meta,
            "extra": self.params.extra,
            "segments": [{"name": "legacy", "start": 0, "end": n, "instruction": task, "subtask_index": subtask}],
            **({"episode_seed": episode.seed} if episode.seed is not None else {}),
        }

    # -- closing ---------------------------------------------------------------------------------
    def finalize(self) -> Optional[str]:
        """Close the dataset (live partial episodes are dropped); idempotent.

        Returns:
            The dataset folder, or ``None`` when no episode was saved.
        """
        if self._finalized:
            return self._path
        self._finalized = True
        dropped = self._buffers.drop(range(self.num_envs))
        if self._encoders is not None:  # every committed episode's videos finished, then they stop
            self._encoders.finalize()
        if self._writer is not None:
            path = self._writer.finalize()
        else:  # nothing was saved; a writer process that was started stops
            path = self._writer_process.finalize() if self._writer_process is not None else None
        self._path = str(path) if path is not None else None
        log.info(
            "%s: saved %d episode(s), %d frame(s) to %s (dropped %d live frame(s))",
            type(self).__name__,
            self.saved_episodes,
            self.saved_frames,
            self._path,
            dropped,
        )
        return self._path
