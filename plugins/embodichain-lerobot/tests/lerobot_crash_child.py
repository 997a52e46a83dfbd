"""A recording process for the crash tests: ``python lerobot_crash_child.py MODE SAVE_PATH FUNC CAMERA [PARAMS]``.

``PARAMS``: more recorder params, as JSON (say ``{"use_videos": true}``).

Prints ``COMMITTED <n>`` (flushed) each time the recorder has saved its n-th
episode; with a writer process also ``WRITER <pid>`` once it has started and ``SENT <n>`` each
time the n-th episode has been handed to it. Modes: ``hang`` (3 episodes, then steps forever inside a 4th),
``churn`` (an episode every 2 steps, forever), ``die_in_save`` / ``die_in_publish``
(SIGKILL itself while saving / publishing the 3rd episode), ``die_in_first_save`` /
``die_in_first_publish`` (the same for the 1st episode), ``die_in_create`` (SIGKILL
right after lerobot created the dataset, before ``meta/info.json`` is published).
The test kills it, or it kills itself.
"""

from __future__ import annotations

import json
import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import torch  # noqa: E402

from lerobot_helpers import arm_cfg, have_sensors, recorder_cfg, reset, stereo_camera  # noqa: E402


def _die_on_episode(cls: type, name: str, saved_before: int) -> None:
    original = getattr(cls, name)

    def wrapper(self, *args, **kwargs):
        if self.num_episodes == saved_before:
            os.kill(os.getpid(), signal.SIGKILL)
        return original(self, *args, **kwargs)

    setattr(cls, name, wrapper)


def _die_in_publish(data_files: int) -> None:
    from embodichain_lerobot import writer

    original = writer.atomic_copy

    def copy(src, dest):
        if dest.name == "info.json" and (dest.parent.parent / "data").exists() and _files(dest) == data_files:
            os.kill(os.getpid(), signal.SIGKILL)
        original(src, dest)

    writer.atomic_copy = copy


def _die_after_create() -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    original = LeRobotDataset.create.__func__

    def create(cls, *args, **kwargs):
        original(cls, *args, **kwargs)
        os.kill(os.getpid(), signal.SIGKILL)

    LeRobotDataset.create = classmethod(create)


def _install_fault(mode: str) -> None:
    from embodichain_lerobot import writer

    if mode in ("die_in_save", "die_in_first_save"):  # lerobot wrote the episode; its writers are open
        _die_on_episode(writer.DatasetWriter, "_continue_in_new_files", 2 if mode == "die_in_save" else 0)
    elif mode in ("die_in_publish", "die_in_first_publish"):  # files moved, info.json not yet replaced
        _die_in_publish(3 if mode == "die_in_publish" else 1)
    elif mode == "die_in_create":
        _die_after_create()


def _files(info_path) -> int:
    return len(list((info_path.parent.parent / "data").glob("*/*.parquet")))


def main(mode: str, save_path: str, func: str, camera: bool, params: dict) -> None:
    _install_fault(mode)
    sensors = [stereo_camera(64, 48)] if camera and have_sensors() else []
    env = __import__("lerobot_helpers").ScriptedEnv(
        arm_cfg(2, dataset=recorder_cfg(save_path, func=func, **params), sensors=sensors, max_episode_steps=10_000)
    )
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    proc = getattr(rec, "_writer_process", None)
    saved, sent, step, writer = 0, 0, 0, None
    try:
        while True:
            step += 1
            done = mode != "hang" or saved < 3
            env.success_flags[:] = torch.tensor([done and step % 2 == 0, done and step % 3 == 0])
            env.step(torch.full(env.action_space.shape, 0.001 * step))
            if rec.saved_episodes > saved:
                saved = rec.saved_episodes
                print(f"COMMITTED {saved}", flush=True)
            if proc is not None and proc._proc is not None and writer is None:  # started by the first reset
                writer = proc._proc.pid
                print(f"WRITER {writer}", flush=True)
            if proc is not None and proc.sent_episodes > sent:
                sent = proc.sent_episodes
                print(f"SENT {sent}", flush=True)  # handed to the writer process, maybe not saved yet
    finally:
        try:
            env.close()
        finally:
            print(f"FINALIZED {rec.saved_episodes} {rec.dataset_path}", flush=True)


if __name__ == "__main__":
    main(
        sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4] == "1", json.loads(sys.argv[5]) if len(sys.argv) > 5 else {}
    )
