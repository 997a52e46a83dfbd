"""A recording process for the crash tests: ``python lerobot_crash_child.py MODE SAVE_PATH FUNC CAMERA``.

Prints ``COMMITTED <n>`` (flushed) each time the recorder has saved its n-th
episode. Modes: ``hang`` (3 episodes, then steps forever inside a 4th),
``churn`` (an episode every 2 steps, forever), ``die_in_save`` / ``die_in_publish``
(SIGKILL itself while saving / publishing the 3rd episode). The test kills it.
"""

from __future__ import annotations

import os
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import torch  # noqa: E402

from lerobot_helpers import arm_cfg, have_sensors, recorder_cfg, reset, stereo_camera  # noqa: E402


def _die_on_third(cls: type, name: str) -> None:
    original = getattr(cls, name)

    def wrapper(self, *args, **kwargs):
        if self.num_episodes == 2:
            os.kill(os.getpid(), signal.SIGKILL)
        return original(self, *args, **kwargs)

    setattr(cls, name, wrapper)


def _install_fault(mode: str) -> None:
    from embodichain_lerobot import writer

    if mode == "die_in_save":  # lerobot has written the episode; its writers are still open
        _die_on_third(writer.DatasetWriter, "_continue_in_new_files")
    elif mode == "die_in_publish":  # data and metadata files moved, info.json not yet replaced
        original = writer.atomic_copy

        def copy(src, dest):
            if dest.name == "info.json" and (dest.parent.parent / "data").exists() and _files(dest) == 3:
                os.kill(os.getpid(), signal.SIGKILL)
            original(src, dest)

        writer.atomic_copy = copy


def _files(info_path) -> int:
    return len(list((info_path.parent.parent / "data").glob("*/*.parquet")))


def main(mode: str, save_path: str, func: str, camera: bool) -> None:
    _install_fault(mode)
    sensors = [stereo_camera(64, 48)] if camera and have_sensors() else []
    env = __import__("lerobot_helpers").ScriptedEnv(arm_cfg(2, dataset=recorder_cfg(save_path, func=func),
                                                            sensors=sensors, max_episode_steps=10_000))
    rec = env.dataset_manager.get_functor("rec")
    reset(env)
    saved, step = 0, 0
    try:
        while True:
            step += 1
            done = mode != "hang" or saved < 3
            env.success_flags[:] = torch.tensor([done and step % 2 == 0, done and step % 3 == 0])
            env.step(torch.full(env.action_space.shape, 0.001 * step))
            if rec.saved_episodes > saved:
                saved = rec.saved_episodes
                print(f"COMMITTED {saved}", flush=True)
    finally:
        env.close()
        print(f"FINALIZED {rec.saved_episodes} {rec.dataset_path}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4] == "1")
