"""``embodichain eval-policy``: record a tiny dataset with ``run-env``, train a tiny ACT on it
with lerobot's own training loop (``lerobot.scripts.lerobot_train.train``), evaluate the
checkpoint in the same gym config; the per-episode results as envs finish at different steps;
the input mapping (depth formats) and its mismatch error; bad policy folders; and the per-env
policy state (ACT's action queue and temporal ensembler, diffusion's observation history)."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
import torch

pytest.importorskip("embodichain_sensors")

from lerobot_helpers import seven_dof_arm_mjcf  # noqa: E402

from embodichain_core.cli import run_env  # noqa: E402
from embodichain_core.envs import EmbodiedEnv  # noqa: E402
from embodichain_lerobot import eval_cli  # noqa: E402
from embodichain_lerobot.policy_state import PerEnvPolicy  # noqa: E402

TINY_ACT = dict(
    chunk_size=4,
    n_action_steps=3,
    dim_model=16,
    n_heads=2,
    dim_feedforward=32,
    n_encoder_layers=1,
    n_decoder_layers=1,
    n_vae_encoder_layers=1,
    latent_dim=4,
    pretrained_backbone_weights=None,
    device="cpu",
    push_to_hub=False,
)


@pytest.fixture(autouse=True)
def one_torch_thread() -> Any:
    """The tiny models run fastest on one thread (several only contend on a busy machine)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def write_config(
    path: Path, task: str, save_path: Path, width: int = 16, height: int = 12, depth: bool = False
) -> Path:
    """2 envs, the arm and one small camera ``head``; a LeRobot recorder."""
    dataset = {
        "lerobot": {
            "func": "LeRobotRecorder",
            "params": {
                "save_path": str(save_path),
                "robot_meta": {"robot_type": "arm7"},
                "instruction": {"lang": "reach forward"},
                "extra": {"scene_type": "empty", "task_description": "reach"},
            },
        }
    }
    camera = {
        "sensor_type": "Camera",
        "uid": "head",
        "width": width,
        "height": height,
        "intrinsics": [width, width, width / 2, height / 2],
        "extrinsics": {"eye": [1.4, 0.0, 1.1], "target": [0.2, 0.0, 0.3]},
        "enable_depth": depth,
    }
    data = {
        "id": task,
        "num_envs": 2,
        "max_episode_steps": 6,
        "max_episodes": 3,
        "demo_max_attempts": 3,
        "env": {"seed": 0, "verbose": False, "control_parts": ["arm"], "dataset": dataset},
        "robot": {"uid": "arm", "mjcf": seven_dof_arm_mjcf(), "control_parts": {"arm": ["joint[1-7]"]}},
        "sensor": [camera],
    }
    path.write_text(json.dumps(data))
    return path


def train_act(dataset: Path, out: Path) -> Path:
    """Two training steps of a tiny ACT through lerobot's training function; the
    pretrained-model folder it saves."""
    from lerobot.configs.default import DatasetConfig, WandBConfig
    from lerobot.configs.train import TrainPipelineConfig
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.scripts.lerobot_train import train

    cfg = TrainPipelineConfig(
        dataset=DatasetConfig(repo_id=f"local/{dataset.name}", root=str(dataset), video_backend="pyav"),
        policy=ACTConfig(**TINY_ACT),
        output_dir=out,
        steps=2,
        batch_size=2,
        save_freq=2,
        num_workers=0,
        log_freq=1,
        eval_freq=0,
        seed=0,
        wandb=WandBConfig(enable=False),
    )
    train(cfg)
    return out / "checkpoints" / "last" / "pretrained_model"


@pytest.fixture
def trained(tmp_path: Path, task_id: str) -> tuple[Path, Path]:
    """(gym config, pretrained-model folder) of a 3-episode dataset recorded from the config."""
    root = tmp_path / "train"
    root.mkdir()
    config = write_config(root / "gen.json", task_id, root / "data")
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    (dataset,) = [p for p in (root / "data").iterdir() if p.is_dir()]
    return config, train_act(dataset, root / "act")


def test_eval_policy_runs_a_trained_act_end_to_end(
    trained: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    config, policy = trained
    assert sorted(p.name for p in policy.iterdir()) >= ["config.json", "model.safetensors"]
    out = tmp_path / "eval.json"
    code = eval_cli.main(
        [
            "--policy",
            str(policy.parents[2]),
            "--gym_config",
            str(config),
            "--episodes",
            "3",
            "--num_envs",
            "2",
            "--seed",
            "1",
            "--headless",
            "--json",
            str(out),
            "--video",
            str(tmp_path / "videos"),
        ]
    )
    assert code == 0, capsys.readouterr().err
    report = json.loads(out.read_text())
    assert report["num_episodes"] == 3
    assert report["instruction"] == "reach forward"  # the recorder's, given to the policy as "task"
    assert [e["episode"] for e in report["episodes"]] == [0, 1, 2]
    assert {e["env_id"] for e in report["episodes"]} == {0, 1}
    assert all(e["length"] == 6 and e["truncated"] and not e["success"] for e in report["episodes"])
    assert report["success_rate"] == 0.0
    assert report["mean_length"] == 6.0
    assert report["env_steps"] == 2 * 12  # episode 2 starts after the first two: 12 batched steps
    assert report["mean_return"] == pytest.approx(sum(e["episode_return"] for e in report["episodes"]) / 3)
    for e in report["episodes"]:
        assert Path(e["video"]).stat().st_size > 0
    stdout = capsys.readouterr().out
    assert "success rate  0.000" in stdout
    assert "mean length   6.0" in stdout


def save_policy(path: Path, state: int = 7, camera: str = "head", image: tuple = (3, 12, 16)) -> Path:
    """An untrained tiny ACT with its processors, saved as lerobot-train saves it."""
    from lerobot.policies.factory import make_pre_post_processors

    policy = tiny_act(inputs={"observation.state": (state,), f"observation.images.{camera}": image}, action=7)
    stats = {
        "observation.state": {"mean": torch.zeros(state), "std": torch.ones(state)},
        f"observation.images.{camera}": {"mean": torch.zeros(3, 1, 1), "std": torch.ones(3, 1, 1)},
        "action": {"mean": torch.zeros(7), "std": torch.ones(7)},
    }
    pre, post = make_pre_post_processors(policy.config, dataset_stats=stats)
    for part in (policy, pre, post):
        part.save_pretrained(path)
    return path


def test_a_policy_whose_inputs_the_env_lacks_is_one_error_listing_both(
    task_id: str, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    config = write_config(tmp_path / "gen.json", task_id, tmp_path / "unused")
    bad = save_policy(tmp_path / "bad", state=9, camera="wrist")
    code = eval_cli.main(["--policy", str(bad), "--gym_config", str(config), "--episodes", "1", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "config error: policy: the policy's inputs do not match the env's observations" in err
    assert "observation.state is [9] for the policy, [7] in the env" in err
    assert "observation.images.wrist [3, 12, 16] is missing" in err
    assert "Policy inputs: observation.images.wrist [3, 12, 16], observation.state [9]" in err
    assert "Env features (the recorder's names): observation.images.head [3, 12, 16]" in err


class QuickWin(EmbodiedEnv):
    """Env 0 succeeds at the 2nd step of each episode, the others time out; reward 1 per step."""

    def compute_task_state(self, **kwargs: Any) -> tuple:
        success = (self.elapsed_steps >= 2) & (torch.arange(self.num_envs) == 0)
        return success, torch.zeros_like(success), {}

    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return torch.ones(self.num_envs)


@pytest.fixture
def quick_win() -> Any:
    import uuid

    import gymnasium as gym

    from embodichain_core.envs.registration import register_env

    uid = f"QuickWin{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(QuickWin)
    yield uid
    gym.registry.pop(uid, None)


def test_results_per_episode_as_the_envs_finish_them(quick_win: str, tmp_path: Path) -> None:
    config = write_config(tmp_path / "win.json", quick_win, tmp_path / "unused")
    policy = save_policy(tmp_path / "policy")
    out = tmp_path / "eval.json"
    assert (
        eval_cli.main(
            [
                "--policy",
                str(policy),
                "--gym_config",
                str(config),
                "--episodes",
                "3",
                "--quiet",
                "--max_steps",
                "4",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    report = json.loads(out.read_text())
    rows = [
        (e["episode"], e["env_id"], e["success"], e["length"], e["episode_return"], e["terminated"], e["truncated"])
        for e in report["episodes"]
    ]
    # env 0 finishes episode 0 at step 2 and starts episode 2; env 1 times out at step 4
    assert rows == [
        (0, 0, True, 2, 2.0, True, False),
        (1, 1, False, 4, 4.0, False, True),
        (2, 0, True, 2, 2.0, True, False),
    ]
    assert report["success_rate"] == pytest.approx(2 / 3)
    assert report["mean_length"] == pytest.approx(8 / 3)
    assert report["mean_return"] == pytest.approx(8 / 3)
    assert report["env_steps"] == 8
    assert (
        eval_cli.main(
            [
                "--policy",
                str(policy),
                "--gym_config",
                str(config),
                "--episodes",
                "1",
                "--quiet",
                "--num_envs",
                "4",
                "--json",
                str(out),
            ]
        )
        == 0
    )
    assert json.loads(out.read_text())["env_steps"] == 2  # --num_envs is at most --episodes
    assert (
        eval_cli.main(
            ["--policy", str(policy), "--gym_config", str(config), "--episodes", "1", "--quiet", "--json", str(out)]
        )
        == 0
    )
    assert json.loads(out.read_text())["env_steps"] == 2  # so is the config's num_envs (2)


def test_depth_inputs_follow_the_recorders_depth_format(task_id: str, tmp_path: Path) -> None:
    """Depth as the packed PNG image feature (the default) or, with ``depth_format: raw``, as numbers."""
    from types import SimpleNamespace

    from lerobot.configs.types import FeatureType, PolicyFeature

    from embodichain_lerobot.packing import pack_depth
    from embodichain_lerobot.policy_inputs import ObservationMapper

    config = write_config(tmp_path / "depth.json", task_id, tmp_path / "unused", depth=True)
    args = eval_cli.build_parser().parse_args(["--policy", "-", "--gym_config", str(config), "--episodes", "2"])
    env = run_env.make_env(eval_cli._plan(args))
    try:
        obs, _ = env.reset(seed=0)
        depth = obs["sensor"]["head"]["depth"]
        image = SimpleNamespace(
            input_features={"observation.depth.head": PolicyFeature(FeatureType.VISUAL, (3, 12, 16))}
        )
        mapped = ObservationMapper(obs, env.unwrapped, image, instruction="reach")(obs)
        assert mapped["task"] == ["reach", "reach"]
        packed = mapped["observation.depth.head"]
        expected = torch.from_numpy(pack_depth(depth.numpy())).permute(0, 3, 1, 2).float() / 255
        torch.testing.assert_close(packed, expected)
        raw = SimpleNamespace(input_features={"observation.depth.head": PolicyFeature(FeatureType.STATE, (12, 16))})
        numbers = ObservationMapper(obs, env.unwrapped, raw)(obs)["observation.depth.head"]
        torch.testing.assert_close(numbers, depth.float().reshape(2, 12, 16))
        assert float(numbers.max()) > 0.1  # metres, not packed bytes
    finally:
        env.close()


def test_a_folder_that_is_no_policy_is_a_config_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = eval_cli.main(["--policy", str(tmp_path / "nope"), "--task", "PushCube-v1", "--episodes", "1"])
    assert code == 2
    assert "does not exist; give the pretrained_model folder lerobot-train writes" in capsys.readouterr().err
    (tmp_path / "half").mkdir()
    (tmp_path / "half" / "config.json").write_text("{}")
    assert eval_cli.main(["--policy", str(tmp_path / "half"), "--task", "PushCube-v1", "--episodes", "1"]) == 2
    assert "missing model.safetensors, policy_preprocessor.json" in capsys.readouterr().err
    for name in ("model.safetensors", "policy_preprocessor.json", "policy_postprocessor.json"):
        (tmp_path / "half" / name).write_text("{}")
    assert eval_cli.main(["--policy", str(tmp_path / "half"), "--task", "PushCube-v1", "--episodes", "1"]) == 1
    assert "while loading the policy from" in capsys.readouterr().err


# -- per-env policy state ----------------------------------------------------------------------------


def tiny_act(inputs: Any = None, action: int = 3, **overrides: Any) -> Any:
    """A tiny ACT (random weights, no backbone download)."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy

    torch.manual_seed(0)
    inputs = inputs or {"observation.state": (5,), "observation.images.head": (3, 8, 8)}
    features = {
        k: PolicyFeature(FeatureType.VISUAL if len(v) == 3 else FeatureType.STATE, tuple(v)) for k, v in inputs.items()
    }
    kwargs = {**TINY_ACT, "chunk_size": 6, "n_action_steps": 4, **overrides}
    return ACTPolicy(
        ACTConfig(
            input_features=features, output_features={"action": PolicyFeature(FeatureType.ACTION, (action,))}, **kwargs
        )
    ).eval()


def batch(t: int, n: int = 3) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(t)
    return {
        "observation.state": torch.randn(n, 5, generator=g),
        "observation.images.head": torch.rand(n, 3, 8, 8, generator=g),
    }


# ACT's queue re-plans every 4 steps: env 1 (reset at step 2) stays off the others' beat. The
# ensembler's state stops growing after chunk_size steps: then all envs batch together again.
@pytest.mark.parametrize(
    "overrides, groups",
    [({}, [[0, 2], [1]]), ({"n_action_steps": 1, "temporal_ensemble_coeff": 0.01}, [[0, 1, 2]])],
    ids=["action_queue", "temporal_ensemble"],
)
def test_per_env_state_resets_one_env_and_keeps_the_others(overrides: dict, groups: list) -> None:
    policy = tiny_act(**overrides)
    together, alone = copy.deepcopy(policy), copy.deepcopy(policy)
    runner = PerEnvPolicy(policy, 3)
    together.reset()
    for t in range(2):  # one group: the same as the policy on the whole batch
        assert runner.groups() == [[0, 1, 2]]
        torch.testing.assert_close(runner.select_action(batch(t)), together.select_action(batch(t)))
    runner.reset([1])
    alone.reset()
    assert runner.groups() == [[0, 2], [1]]
    for t in range(2, 9):
        actions = runner.select_action(batch(t))
        torch.testing.assert_close(actions[[0, 2]], together.select_action(batch(t))[[0, 2]])
        torch.testing.assert_close(actions[1:2], alone.select_action({k: v[1:2] for k, v in batch(t).items()}))
    assert runner.groups() == groups


def test_per_env_state_restarts_one_envs_observation_history() -> None:
    """Diffusion keeps the last ``n_obs_steps`` observations: a reset env's history restarts
    from its new observation (lerobot fills an empty queue with copies), the others' goes on."""
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy

    torch.manual_seed(0)
    inputs = {
        "observation.state": PolicyFeature(FeatureType.STATE, (5,)),
        "observation.images.head": PolicyFeature(FeatureType.VISUAL, (3, 32, 32)),
    }
    policy = DiffusionPolicy(
        DiffusionConfig(
            input_features=inputs,
            output_features={"action": PolicyFeature(FeatureType.ACTION, (3,))},
            device="cpu",
            crop_shape=None,
            pretrained_backbone_weights=None,
            down_dims=(8, 16),
            num_inference_steps=2,
            n_obs_steps=2,
            horizon=8,
            n_action_steps=4,
            diffusion_step_embed_dim=8,
            spatial_softmax_num_keypoints=4,
        )
    ).eval()
    runner = PerEnvPolicy(policy, 3)

    def obs(t: int) -> dict[str, torch.Tensor]:
        return {
            "observation.state": torch.full((3, 5), float(t)),
            "observation.images.head": torch.rand(3, 3, 32, 32, generator=torch.Generator().manual_seed(t)),
        }

    def history(env: int) -> list[float]:
        return [float(row[0, 0]) for row in runner.state_of(env)["_queues"]["observation.state"]]

    runner.select_action(obs(0))
    runner.select_action(obs(1))
    assert [history(i) for i in range(3)] == [[0.0, 1.0]] * 3
    runner.reset([1])
    assert runner.select_action(obs(2)).shape == (3, 3)
    assert [history(i) for i in range(3)] == [[1.0, 2.0], [2.0, 2.0], [1.0, 2.0]]
    assert runner.groups() == [[0, 2], [1]]


def test_each_episode_keeps_the_task_metrics_of_its_last_step() -> None:
    from embodichain_lerobot.eval_policy import _episode_metrics

    metrics = {
        "fork_height": torch.tensor([0.1234567, -0.002]),
        "per_joint": torch.zeros(2, 3),  # not one value per env: left out
        "lifted": torch.tensor([True, False]),  # not a number to report
    }
    assert _episode_metrics(metrics, 2) == [{"fork_height": 0.12346}, {"fork_height": -0.002}]
    assert _episode_metrics(None, 2) == [{}, {}]
