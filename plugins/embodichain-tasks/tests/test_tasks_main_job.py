"""The main job's config (`make run`): PickFork-v1 with a LeRobot recorder."""

from pathlib import Path

import embodichain_tasks

from embodichain_core.config.loader import load_gym_config

MAIN_JOB = Path(embodichain_tasks.__file__).parent / "configs" / "main_job.json"


def test_main_job_records_pick_fork_demos_with_the_stereo_camera_as_video():
    task_id, cfg, extras = load_gym_config(str(MAIN_JOB))
    assert task_id == "PickFork-v1"
    assert cfg.num_envs == 2
    assert extras["max_episodes"] >= 2
    recorder = cfg.dataset["lerobot"]
    assert recorder.func == "AsyncLeRobotRecorder"  # its writer process encodes beside stepping
    assert recorder.params["use_videos"] is True
    assert recorder.params["vcodec"] == "h264"
    assert recorder.params["environment_state"] == ["fork_pose"]  # what state-based policies read
    assert [s.sensor_type for s in cfg.sensor] == ["StereoCamera"]
