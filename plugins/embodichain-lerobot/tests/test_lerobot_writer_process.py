"""The writer process's parts: episodes as columns, frames routed to each env's encoder,
restarts, a dead child, errors that do not pickle."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from embodichain_lerobot.episodes import EpisodeBuffers, StepData
from embodichain_lerobot.lossless_video import RoutedEncoder
from embodichain_lerobot.storage import DiskFullError
from embodichain_lerobot.child_io import _picklable
from embodichain_lerobot.writer_child import ChildWriter
from embodichain_lerobot.writer_process import WriterProcess, WriterProcessError, from_columns, to_columns


def test_columns_round_trip_and_leave_out_streamed_features() -> None:
    frames = [{"img": np.full((2, 2, 3), t, np.uint8), "x": np.array([t], np.float32), "task": "go"} for t in range(3)]
    columns, length = to_columns(frames, skip=["img"])
    assert length == 3
    assert set(columns) == {"x", "task"}
    assert columns["x"].shape == (3, 1)
    back = list(from_columns(columns, length, {"img": "dummy"}))
    assert [float(f["x"][0]) for f in back] == [0.0, 1.0, 2.0]
    assert all(f["task"] == "go" and f["img"] == "dummy" for f in back)


def test_pending_groups_pair_each_env_with_the_observation_it_acted_on() -> None:
    buffers = EpisodeBuffers(3)
    first, second = {"o": np.zeros((3, 1))}, {"o": np.ones((3, 1))}
    assert buffers.pending_groups() == []
    buffers.start(first, [0, 1, 2])
    step = StepData(*(np.zeros(3) for _ in range(5)))
    buffers.add(second, step)
    buffers.start(first, [1])  # env 1 reset: it acts on the reset observation next
    groups = buffers.pending_groups()
    assert [(snap is second, ids) for snap, ids in groups] == [(True, [0, 2]), (False, [1])]


class FakeEncoder:
    """Records what lerobot's streaming encoder would get."""

    def __init__(self, **settings: Any):
        self.settings, self.frames, self.calls = settings, [], []

    def start_episode(self, video_keys: Any, temp_dir: Any) -> None:
        self.calls.append("start")

    def feed_frame(self, key: str, image: np.ndarray) -> None:
        assert image.shape[-1] == 3  # RGBA batches lose their alpha before the encoder
        self.frames.append((key, int(image[0, 0, 0])))

    def cancel_episode(self) -> None:
        self.calls.append("cancel")


class FakeEncoderBase(FakeEncoder):
    fps, vcodec, pix_fmt, g, crf, preset, queue_maxsize, encoder_threads = 30, "h264", "yuv420p", 2, 30, None, 0, None


def child_with_fake_dataset(tmp_path: Path) -> ChildWriter:
    child = ChildWriter()
    dataset = type("DS", (), {"_streaming_encoder": RoutedEncoder(FakeEncoderBase()), "root": tmp_path})()
    child.writer = type("W", (), {"dataset": dataset})()
    child.streamed = ["cam"]
    return child


def test_streamed_frames_reach_their_own_envs_encoder(tmp_path: Path) -> None:
    child = child_with_fake_dataset(tmp_path)
    frames = np.stack([np.full((2, 2, 4), 10 + env, np.uint8) for env in range(3)])  # RGBA, as the recorder sends
    child.handle("frames", ({"cam": frames[[0, 2]]}, [0, 2]))  # env 1 has no frame this step
    child.handle("frames", ({"cam": frames[[2]]}, [2]))
    colour = {env: encoder.colour for env, encoder in child.encoders.items()}
    assert colour[0].frames == [("cam", 10)]
    assert colour[2].frames == [("cam", 12), ("cam", 12)]
    assert colour[0].calls == ["start"]
    assert 1 not in child.encoders
    assert colour[0].settings["queue_maxsize"] == 0  # never drops a frame
    child.handle("restart", [0, 1])  # env 0's live episode is dropped; env 1 has none
    child.handle("frames", ({"cam": frames[[0]]}, [0]))
    assert colour[0].calls == ["start", "cancel", "start"]
    assert child.live == {0, 2}


def test_errors_that_do_not_pickle_keep_their_text_and_disk_full_stays_disk_full() -> None:
    class Local(Exception):  # defined in a function: pickle cannot find it
        pass

    err = _picklable(Local("bad frame"))
    assert isinstance(err, WriterProcessError)
    assert "Local: bad frame" in str(err)
    full = DiskFullError(28, "no space")
    assert _picklable(full) is full


def test_a_dead_writer_process_fails_the_waiting_calls(tmp_path: Path) -> None:
    proc = WriterProcess()
    proc.start()
    proc._proc.kill()  # type: ignore[union-attr]
    done = threading.Event()
    future = proc.submit("finalize", None)
    future.add_done_callback(lambda f: done.set())
    assert done.wait(30)
    with pytest.raises(WriterProcessError, match=r"the dataset writer process exited \(code -9; .*no dataset yet"):
        future.result()
    with pytest.raises(WriterProcessError):
        proc.submit("finalize", None).result(5)
