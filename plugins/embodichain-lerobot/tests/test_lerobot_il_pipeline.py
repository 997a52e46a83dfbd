"""The imitation pipeline: rates with intervals, checkpoint choice, recipes, the curve, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from embodichain_lerobot.il_pipeline import CAMERA_CONFIG, MAIN_JOB, main
from embodichain_lerobot.il_plots import plot_success_curve
from embodichain_lerobot.il_recipes import camera_uids, pipeline_config, train_flags
from embodichain_lerobot.il_stats import choose_checkpoint, format_rate, rate_summary, wilson_interval


def test_wilson_interval_matches_known_values_and_is_bounded() -> None:
    lo, hi = wilson_interval(55, 100)
    assert (round(lo, 3), round(hi, 3)) == (0.452, 0.644)
    assert wilson_interval(0, 20)[0] == 0.0
    assert 0.15 < wilson_interval(0, 20)[1] < 0.17
    assert wilson_interval(20, 20)[1] == 1.0
    assert 0.83 < wilson_interval(20, 20)[0] < 0.85
    assert wilson_interval(0, 0) == (0.0, 1.0)
    narrow, wide = wilson_interval(50, 100), wilson_interval(5, 10)
    assert narrow[1] - narrow[0] < wide[1] - wide[0]  # more episodes, a tighter interval
    with pytest.raises(ValueError, match="successes"):
        wilson_interval(11, 10)


def test_rate_summary_lists_every_episode_and_the_choice_uses_validation_only() -> None:
    episodes = [
        {"episode_seed": 7, "success": True, "length": 120},
        {"episode_seed": 8, "success": False, "length": 300},
    ]
    summary = rate_summary(episodes)
    assert summary["success_rate"] == 0.5
    assert summary["successes"] == 1
    assert summary["episodes"] == 2
    assert summary["per_episode"] == [
        {"seed": 7, "success": True, "length": 120},
        {"seed": 8, "success": False, "length": 300},
    ]
    assert format_rate(summary).startswith("0.50 [0.09, 0.91] (1/2)")
    rows = [
        {"step": 1000, "success_rate": 0.4},
        {"step": 2000, "success_rate": 0.6},
        {"step": 3000, "success_rate": 0.6},
    ]
    assert choose_checkpoint(rows)["step"] == 3000  # a tie goes to the later step
    with pytest.raises(ValueError, match="no checkpoint"):
        choose_checkpoint([])


def test_the_camera_recipe_keeps_the_named_camera_and_records_no_object_pose() -> None:
    assert CAMERA_CONFIG is not None
    assert CAMERA_CONFIG.is_file()
    assert camera_uids(json.loads(CAMERA_CONFIG.read_text())) == ["eye_in_head", "policy_cam"]
    data = pipeline_config(CAMERA_CONFIG, "camera", ["policy_cam"])
    assert [s["uid"] for s in data["sensor"]] == ["policy_cam"]
    params = data["env"]["dataset"]["lerobot"]["params"]
    assert "environment_state" not in params
    assert params["use_videos"] is True
    flags = train_flags("camera")
    assert "--policy.pretrained_backbone_weights=null" in flags  # nothing is downloaded
    names = [f.split("=", 1)[0] for f in flags]
    assert len(names) == len(set(names))  # each flag once
    assert any(f.startswith("--dataset.image_transforms.tfs=") for f in flags)
    assert not any("image_transforms" in f for f in train_flags("state"))
    for recipe in ("state", "camera"):  # both plan every step and average the chunks (temporal ensembling)
        assert {"--policy.n_action_steps=1", "--policy.temporal_ensemble_coeff=0.01"} <= set(train_flags(recipe))


def test_bad_camera_input_names_the_sensor_key_and_the_cameras_there(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="sensor: no camera 'wrist'.*eye_in_head, policy_cam"):
        pipeline_config(CAMERA_CONFIG, "camera", ["wrist"])
    assert MAIN_JOB is not None
    plain = json.loads(MAIN_JOB.read_text())
    plain["sensor"] = []
    (tmp_path / "c.json").write_text(json.dumps(plain))
    with pytest.raises(ValueError, match="sensor: the config has no camera"):
        pipeline_config(tmp_path / "c.json", "camera", ["policy_cam"])
    with pytest.raises(ValueError, match="unknown recipe 'pixels'"):
        pipeline_config(CAMERA_CONFIG, "pixels")


def test_the_pipeline_stops_before_any_step_on_a_config_without_a_camera(tmp_path: Path, capsys) -> None:
    plain = json.loads(MAIN_JOB.read_text())
    plain["sensor"] = []
    (tmp_path / "c.json").write_text(json.dumps(plain))
    with pytest.raises(SystemExit) as err:
        main(["--out", str(tmp_path / "run"), "--policy", "camera", "--config", str(tmp_path / "c.json")])
    assert err.value.code == 2
    assert "sensor: the config has no camera" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()  # nothing half-built


def test_the_pick_fork_state_default_reads_the_fork_pose_and_its_centre_of_mass(tmp_path: Path) -> None:
    from embodichain_lerobot.il_pipeline import STATE_CONFIG, _check_args, build_parser

    parser = build_parser()
    args = parser.parse_args(["--out", str(tmp_path)])
    _check_args(parser, args)
    assert args.config == STATE_CONFIG
    params = pipeline_config(STATE_CONFIG, "state")["env"]["dataset"]["lerobot"]["params"]
    assert params["environment_state"] == ["fork_pose", "fork_com"]


def test_the_open_drawer_state_recipe_reads_the_handle_and_the_opening_and_renders_nothing() -> None:
    config = MAIN_JOB.parent / "open_drawer_record.json"
    data = pipeline_config(config, "state")
    assert data["sensor"] == []
    params = data["env"]["dataset"]["lerobot"]["params"]
    assert params["environment_state"] == ["handle_pose", "drawer_opening"]
    assert params["use_videos"] is False


def test_config_by_shipped_name_and_a_wrong_name_lists_the_shipped_ones(tmp_path: Path, capsys) -> None:
    from embodichain_lerobot.il_pipeline import _check_args, build_parser

    parser = build_parser()
    args = parser.parse_args(["--out", str(tmp_path), "--config", "open_drawer_record.json"])
    _check_args(parser, args)
    assert args.config == MAIN_JOB.parent / "open_drawer_record.json"
    with pytest.raises(SystemExit):
        _check_args(parser, parser.parse_args(["--out", str(tmp_path), "--config", "open_drawer_recrd.json"]))
    err = capsys.readouterr().err
    assert "--config: no file 'open_drawer_recrd.json'" in err
    assert "open_drawer_record.json" in err  # the closest valid choice is listed


def test_the_success_curve_is_a_plot_with_interval_bars(tmp_path: Path) -> None:
    from PIL import Image

    val = [
        {"step": 1000, "success_rate": 0.2, "ci95": [0.11, 0.33], "episodes": 50},
        {"step": 2000, "success_rate": 0.6, "ci95": [0.46, 0.72], "episodes": 50},
    ]
    test = {"step": 2000, "success_rate": 0.55, "ci95": [0.45, 0.64], "episodes": 100}
    png = plot_success_curve(val, test, tmp_path / "curve.png", "PickFork-v1")
    image = Image.open(png)
    assert image.size == (770, 462)  # 7 x 4.2 inches at 110 dpi
    assert len(image.convert("RGB").getcolors(maxcolors=1 << 16) or []) > 50  # axes, text, markers: not blank


def test_the_visual_randomization_table_is_a_bar_plot_with_interval_bars(tmp_path: Path) -> None:
    from PIL import Image

    from embodichain_lerobot.il_plots import plot_rate_table

    cell = {"success_rate": 0.5, "ci95": [0.4, 0.6], "episodes": 100}
    cells = {f"{p}/{s}": cell for p in ("randomized", "plain") for s in ("nominal", "shifted")}
    image = Image.open(plot_rate_table(cells, tmp_path / "table.png", "PickFork-v1"))
    assert image.size == (770, 462)
    # two colours of bars, their labels, axes and text: far from a blank or one-colour image
    assert len(image.convert("RGB").getcolors(maxcolors=1 << 16) or []) > 50
    with pytest.raises(KeyError, match="plain/shifted"):  # a missing cell is not drawn as a zero
        plot_rate_table({k: v for k, v in cells.items() if k != "plain/shifted"}, tmp_path / "t.png", "x")


def test_the_camera_pipeline_runs_end_to_end(tmp_path: Path) -> None:
    """Generate 2 demos with the 96x96 policy camera, train 2 steps, validate and test 1 episode each."""
    out = tmp_path / "run"
    argv = ["--out", str(out), "--policy", "camera", "--demos", "2", "--workers", "1", "--num_envs", "1"]
    argv += ["--steps", "2", "--save_freq", "2", "--batch_size", "2", "--val_episodes", "1", "--test_episodes", "1"]
    argv += ["--max_steps", "10"]  # an untrained policy would use all 300 steps
    assert main(argv) == 0
    results = json.loads((out / "results.json").read_text())
    assert results["recipe"] == "camera"
    assert results["cameras"] == ["policy_cam"]
    assert results["chosen_step"] == 2
    assert len(results["checkpoints"]) == 1
    (episode,) = results["test"]["per_episode"]
    assert episode["length"] == 10
    assert set(episode) == {"seed", "success", "length"}
    assert isinstance(episode["seed"], int)
    assert results["seeds_shared"] == {"validation_training": 0, "test_training": 0, "test_validation": 0}
    assert set(results["seconds"]) == {"generate", "train", "validate", "test"}
    lo, hi = results["test"]["ci95"]
    assert 0.0 <= lo <= results["test"]["success_rate"] <= hi <= 1.0
    policy_cfg = json.loads((Path(results["chosen_policy"]) / "config.json").read_text())
    inputs = policy_cfg["input_features"]
    assert {"observation.state", "observation.images.policy_cam"} <= set(inputs)
    assert "observation.environment_state" not in inputs  # no object pose
    assert inputs["observation.images.policy_cam"]["shape"] == [3, 96, 96]
    assert policy_cfg["temporal_ensemble_coeff"] == 0.01
    assert (out / "success_curve.png").stat().st_size > 10_000


def test_the_shifted_scene_replaces_the_visual_randomization_and_builds(tmp_path: Path) -> None:
    import gymnasium as gym

    from embodichain_core.config.loader import load_gym_config
    from embodichain_lerobot.il_visual import SHIFT, nominal_scene, shifted_scene
    from embodichain_tasks.il.pick_fork import PickForkCfg

    base = pipeline_config(CAMERA_CONFIG, "camera", ["policy_cam"])
    assert nominal_scene(base)["env"]["filter_visual_rand"] is True
    shifted = shifted_scene(base, ["policy_cam"])
    events = shifted["env"]["events"]
    assert {"light", "table_material"}.isdisjoint(events)  # the training ranges are gone
    assert {"fork_pose", "fork_mass", "replace_fork"} <= set(events)  # physical randomization stays
    assert events["shift_light"]["params"]["intensity_range"] == SHIFT["light_intensity_range"]
    assert events["shift_camera_policy_cam"]["params"]["entity_cfg"] == {"uid": "policy_cam"}
    shifted["env"].pop("dataset")
    task_id, cfg, _ = load_gym_config(shifted, {"num_envs": 1}, cfg_cls=PickForkCfg)
    env = gym.make(task_id, cfg=cfg, verbose=False)
    try:
        obs, _ = env.reset(seed=0)
        active = env.unwrapped.event_manager.active_functors
        assert {"shift_table", "shift_light", "shift_camera_policy_cam"} <= set(active)
        assert obs["sensor"]["policy_cam"]["color"].shape[-3:-1] == (96, 96)
    finally:
        env.close()


def test_the_cosine_schedule_is_flags_lerobot_train_parses_into_a_decay_over_the_steps() -> None:
    import draccus
    from lerobot.configs.train import TrainPipelineConfig
    from lerobot.policies.act.configuration_act import ACTConfig  # registers --policy.type=act

    flags = train_flags("state", "cosine", 4000)
    assert set(train_flags("state")) < set(flags)  # the recipe's ACT flags, plus the schedule
    cfg = draccus.parse(TrainPipelineConfig, args=[*flags, "--dataset.repo_id=local/demos", "--steps=4000"])
    assert isinstance(cfg.policy, ACTConfig)
    assert cfg.use_policy_training_preset is False
    assert (cfg.optimizer.lr, cfg.optimizer.weight_decay, cfg.optimizer.grad_clip_norm) == (1e-4, 1e-4, 10.0)
    assert (cfg.scheduler.num_decay_steps, cfg.scheduler.decay_lr) == (4000, 1e-6)
    with pytest.raises(ValueError, match="lr_schedule: unknown schedule 'cosin'; choose one of constant, cosine"):
        train_flags("state", "cosin", 4000)
    with pytest.raises(ValueError, match="camera recipe trains at a constant rate"):
        train_flags("camera", "cosine", 4000)


def test_an_eval_config_by_shipped_name_is_where_validation_and_test_run(tmp_path: Path, capsys) -> None:
    from embodichain_lerobot.il_pipeline import _check_args, _Stages, build_parser

    parser = build_parser()
    args = parser.parse_args(["--out", str(tmp_path), "--eval_config", "pick_fork_state_eef.json"])
    _check_args(parser, args)
    assert args.eval_config == MAIN_JOB.parent / "pick_fork_state_eef.json"
    assert _Stages(args, tmp_path).eval_config == tmp_path / "eval_config.json"
    plain = parser.parse_args(["--out", str(tmp_path)])
    _check_args(parser, plain)
    assert _Stages(plain, tmp_path).eval_config == tmp_path / "config.json"
    with pytest.raises(SystemExit):
        _check_args(parser, parser.parse_args(["--out", str(tmp_path), "--eval_config", "pick_fork_stat.json"]))
    err = capsys.readouterr().err
    assert "--eval_config: no file 'pick_fork_stat.json'" in err
    assert "pick_fork_state.json" in err


def test_the_chunk_size_is_one_flag_lerobot_train_parses(tmp_path: Path, capsys) -> None:
    import draccus
    from lerobot.configs.train import TrainPipelineConfig
    from lerobot.policies.act.configuration_act import ACTConfig  # noqa: F401  (registers act)

    from embodichain_lerobot.il_pipeline import _check_args, build_parser

    for policy in ("state", "camera"):
        flags = train_flags(policy, chunk_size=100)
        assert [f for f in flags if f.startswith("--policy.chunk_size")] == ["--policy.chunk_size=100"]
        cfg = draccus.parse(TrainPipelineConfig, args=[*flags, "--dataset.repo_id=local/demos"])
        assert cfg.policy.chunk_size == 100
    assert "--policy.chunk_size=20" in train_flags("state")
    with pytest.raises(ValueError, match="chunk_size: at least 1 action per chunk, got 0"):
        train_flags("state", chunk_size=0)
    parser = build_parser()
    with pytest.raises(SystemExit):
        _check_args(parser, parser.parse_args(["--out", str(tmp_path), "--chunk_size", "0"]))
    assert "--chunk_size must be at least 1, got 0" in capsys.readouterr().err
