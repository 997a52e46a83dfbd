"""Messages of ``embodichain generate`` without Ray: plain progress lines and the words for a dead worker."""

from __future__ import annotations

import io

from embodichain_ray.faults import death_reason, worker_death_note
from embodichain_ray.progress import PlainProgress, format_duration


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_plain_progress_prints_at_the_first_episode_then_every_interval_and_at_the_end() -> None:
    out, clock = io.StringIO(), Clock()
    bar = PlainProgress(10, initial=2, every=30.0, out=out, clock=clock)
    clock.now += 10
    bar.update(1)  # the first saved episode: a line at once
    clock.now += 10
    bar.update(1)  # 10 s later: not due
    clock.now += 30
    bar.update(2)
    clock.now += 5
    bar.update(4)  # the last one: a line whatever the interval
    assert out.getvalue().splitlines() == [
        "generate: 3/10 episode(s) saved (30%), 0.10 episode(s)/s, ETA 1m10s",
        "generate: 6/10 episode(s) saved (60%), 0.08 episode(s)/s, ETA 50s",
        "generate: 10/10 episode(s) saved (100%), 0.15 episode(s)/s, ETA done",
    ]


def test_durations_read_as_seconds_minutes_or_hours() -> None:
    assert [format_duration(s) for s in (4.4, 209, 7500)] == ["4s", "3m29s", "2h05m"]


RAY_TEXT = (
    "The actor died unexpectedly before finishing this task.\n\tclass_name: EpisodeWorker\n\tpid: 4242\n"
    "\tThe actor is dead because its worker process has died. Worker exit type: SYSTEM_ERROR "
    "Worker exit detail: RpcError: RPC Error message: Socket closed; RPC Error details:  rpc_code: 14"
)


def test_a_dead_worker_is_told_in_words_with_its_episodes_and_what_happens_next() -> None:
    err = RuntimeError(RAY_TEXT)
    assert death_reason(err) == "its process died (pid 4242): killed, or it crashed"
    note = worker_death_note(1, [4, 5], err, restarts=1, limit=3, requeue=True, gone=False)
    assert note == (
        "worker 1 died while running episode(s) 4, 5 (its process died (pid 4242): killed, or it crashed); "
        "Ray restarts it (restart 1 of 3) and they run again"
    )
    assert "RpcError" not in note
    assert "rpc_code" not in note
    assert worker_death_note(1, [4], err, 2, 3, requeue=False, gone=False).endswith("the run is stopping")
    assert worker_death_note(1, None, err, 4, 3, requeue=True, gone=False) == ""  # a probe: already told
    gone = worker_death_note(1, None, err, 4, 3, requeue=True, gone=True)
    assert gone.startswith("worker 1 is gone for good")
    assert "--max-restarts 3" in gone


def test_a_worker_that_cannot_build_its_env_says_why() -> None:
    err = RuntimeError(
        "The actor died because of an error raised in its creation task, ray::EpisodeWorker.__init__()\n"
        "Traceback ...\nValueError: asset folder TableWare/ not found"
    )
    assert death_reason(err) == "building its env failed: ValueError: asset folder TableWare/ not found"
    assert "out of memory" in death_reason(RuntimeError("Task was killed due to the node running low on memory. OOM"))
