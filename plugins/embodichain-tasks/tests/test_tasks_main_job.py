"""The main job's config (`make run`): PickFork-v1 with a LeRobot recorder."""

import json
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


def _load(name: str) -> dict:
    return json.loads((MAIN_JOB.parent / name).read_text(encoding="utf-8"))


def test_pick_fork_state_config_is_the_main_job_plus_the_fork_centre_of_mass():
    """pick_fork_state.json is a copy of main_job.json with one observation more: undoing
    that change must give main_job.json back, so the two cannot drift apart unseen."""
    state = _load("pick_fork_state.json")
    assert state["env"]["observations"].pop("fork_com")["func"] == "embodichain_tasks.il.pick_fork:fork_com"
    recorder = state["env"]["dataset"]["lerobot"]["params"]
    assert recorder["environment_state"] == ["fork_pose", "fork_com"]
    recorder["environment_state"] = ["fork_pose"]
    assert state == _load("main_job.json")


def test_pick_fork_camera_config_is_the_main_job_plus_a_policy_camera():
    camera = _load("pick_fork_camera.json")
    policy_cam = [s for s in camera["sensor"] if s["uid"] == "policy_cam"]
    assert len(policy_cam) == 1
    assert policy_cam[0]["width"] == policy_cam[0]["height"] == 96
    camera["sensor"] = [s for s in camera["sensor"] if s["uid"] != "policy_cam"]
    assert camera == _load("main_job.json")


def test_pick_fork_state_eef_config_is_the_state_config_plus_an_eef_pose_action():
    eef = _load("pick_fork_state_eef.json")
    term = eef["env"].pop("actions")["eef_pose"]
    assert term == {"func": "EefPoseTerm", "params": {"part_name": "right_arm", "gripper_part": "right_eef"}}
    assert eef == _load("pick_fork_state.json")


def test_pick_fork_state_eef_perturbed_is_the_eef_config_plus_perturbed_arm_starts():
    perturbed = _load("pick_fork_state_eef_perturbed.json")
    event = perturbed["env"]["events"].pop("arm_start")
    assert event["func"] == "randomize_robot_eef_pose"
    assert event["mode"] == "reset"
    assert event["params"]["position_range"] == [[-0.04, -0.04, -0.03], [0.04, 0.04, 0.03]]
    assert perturbed == _load("pick_fork_state_eef.json")


def test_pick_fork_state_eef_dart_is_the_eef_config_plus_execution_noise_over_the_reach():
    dart = _load("pick_fork_state_eef_dart.json")
    params = dart["env"]["actions"]["eef_pose"]["params"]
    assert (params.pop("noise_std"), params.pop("noise_tau"), params.pop("noise_steps")) == (0.005, 10.0, 35)
    assert dart == _load("pick_fork_state_eef.json")
