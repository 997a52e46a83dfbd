"""lerobot's own commands on an embodichain task (``--env.type=embodichain``): ``lerobot-eval``
and ``lerobot-train``'s periodic evaluation run a tiny ACT trained 2 steps on 2 recorded
episodes; ``lerobot-eval`` and ``embodichain eval-policy`` agree episode by episode; an
unknown task or a policy input the env lacks stops the command before any episode."""

from __future__ import annotations

import json
import sys
import uuid
from pathlib import Path
from typing import Any, Iterator

import pytest
import torch

pytest.importorskip("embodichain_sensors")

from test_lerobot_eval_policy import TINY_ACT, save_policy, train_act, write_config  # noqa: E402
from test_lerobot_run_env import DemoPush  # noqa: E402

from embodichain_core.cli import run_env  # noqa: E402
from embodichain_lerobot.lerobot_env import EnvConfigError  # noqa: E402
from embodichain_core.envs.episode_rng import derive_seed  # noqa: E402
from embodichain_lerobot import eval_cli  # noqa: E402

ENV_ARGS = ["--env.discover_packages_path=embodichain_lerobot.lerobot_env", "--env.type=embodichain"]


class SeedWin(DemoPush):
    """Succeeds at the 2nd step of an episode whose episode seed is even; the others time out.
    The reward is the sum of the action: equal returns mean the policy acted the same."""

    def compute_task_state(self, **kwargs: Any) -> tuple:
        even = torch.as_tensor(self.episode_seeds % 2 == 0)
        success = (self.elapsed_steps >= 2) & even
        return success, torch.zeros_like(success), {}

    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return torch.as_tensor(action, dtype=torch.float32).reshape(self.num_envs, -1).sum(-1)


def _register(cls: type) -> str:
    from embodichain_core.envs.registration import register_env

    uid = f"{cls.__name__}{uuid.uuid4().hex[:8]}-v0"
    register_env(uid)(cls)
    return uid


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Path]]:
    """The eval config (``SeedWin``) and a 2-episode dataset recorded from ``DemoPush`` with
    the same robot and camera."""
    import gymnasium as gym

    root = tmp_path_factory.mktemp("lerobot_env")
    demo, win = _register(DemoPush), _register(SeedWin)
    config = write_config(root / "gen.json", demo, root / "data")
    data = json.loads(config.read_text())
    config.write_text(json.dumps({**data, "max_episodes": 2}))
    assert run_env.main(["--gym_config", str(config), "--quiet"]) == 0
    (dataset,) = [p for p in (root / "data").iterdir() if p.is_dir()]
    eval_config = write_config(root / "eval.json", win, root / "unused")
    yield {"config": eval_config, "dataset": dataset, "gen_config": config, "root": root}
    for uid in (demo, win):
        gym.registry.pop(uid, None)


@pytest.fixture(scope="module")
def tiny(recorded: dict[str, Path]) -> dict[str, Path]:
    """:func:`recorded` and a tiny ACT trained 2 steps on its dataset."""
    return {**recorded, "policy": train_act(recorded["dataset"], recorded["dataset"].parents[1] / "act")}


def state_only(config: Path, out: Path) -> Path:
    """``config`` without its camera, the recorder listing ``robot/qvel`` as the environment state
    (what a state-based ACT needs besides ``observation.state``), as the state pipeline's config."""
    data = json.loads(config.read_text())
    data.pop("sensor")
    data["env"]["dataset"]["lerobot"]["params"]["environment_state"] = ["robot/qvel"]
    data["env"]["dataset"]["lerobot"]["params"]["save_path"] = str(out.parent / "state_data")
    out.write_text(json.dumps(data))
    return out


@pytest.fixture(scope="module")
def tiny_state(recorded: dict[str, Path]) -> dict[str, Path]:
    """A state-only ACT (``observation.state`` + ``observation.environment_state``) trained 2 steps
    on 2 episodes recorded without a camera, and the matching eval config."""
    root = recorded["root"]
    gen = state_only(recorded["gen_config"], root / "state_gen.json")
    assert run_env.main(["--gym_config", str(gen), "--quiet"]) == 0
    (dataset,) = [p for p in (root / "state_data").iterdir() if p.is_dir()]
    config = state_only(recorded["config"], root / "state_eval.json")
    return {"config": config, "dataset": dataset, "policy": train_act(dataset, root / "state_act")}


def lerobot(module: str, argv: list[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Run the console script ``lerobot-<module>`` (its ``main``) in this process."""
    import importlib

    main = importlib.import_module(f"lerobot.scripts.lerobot_{module}").main
    monkeypatch.setattr(sys, "argv", [f"lerobot-{module}", *argv])
    main()


def lerobot_eval(tiny: dict[str, Path], out: Path, monkeypatch: pytest.MonkeyPatch, *extra: str) -> dict:
    args = [
        *ENV_ARGS,
        f"--env.gym_config={tiny['config']}",
        f"--policy.path={tiny['policy']}",
        "--policy.device=cpu",
        "--eval.n_episodes=4",
        "--eval.batch_size=2",
        "--seed=7",
        f"--output_dir={out}",
        *extra,
    ]
    lerobot("eval", args, monkeypatch)
    return json.loads((out / "eval_info.json").read_text())


@pytest.mark.slow  # ~30 s on 2 cores: records and trains the tiny policy, then evaluates
@pytest.mark.parametrize("policy", ["camera", "state"])
def test_lerobot_eval_runs_our_env_and_agrees_with_eval_policy(
    policy: str, request: pytest.FixtureRequest, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The camera policy reads ``observation.images.head`` + ``.state``, the state policy
    ``observation.state`` + ``.environment_state`` in a config without camera (videos of the scene)."""
    tiny = request.getfixturevalue("tiny" if policy == "camera" else "tiny_state")
    inputs = json.loads((tiny["policy"] / "config.json").read_text())["input_features"]
    assert ("observation.images.head" in inputs) == (policy == "camera")
    assert ("observation.environment_state" in inputs) == (policy == "state")
    info = lerobot_eval(tiny, tmp_path / "eval", monkeypatch)
    (task,) = info["per_task"]
    metrics = task["metrics"]  # episode k ran with seed 7 + k (lerobot's --seed)
    assert len(metrics["successes"]) == info["overall"]["n_episodes"] == 4
    assert metrics["video_paths"]
    assert all(Path(p).stat().st_size > 0 for p in metrics["video_paths"])
    successes = [bool(s) for s in metrics["successes"]]
    assert 0 < sum(successes) < 4, successes  # both outcomes occur: the success flag is what decides
    assert successes == [int(derive_seed(7 + k, 0, 0)) % 2 == 0 for k in range(4)]
    # eval-policy on each of lerobot's episode seeds (one env, one episode each)
    ours = []
    for k in range(4):
        out = tmp_path / f"ours{k}.json"
        argv = ["--policy", str(tiny["policy"]), "--gym_config", str(tiny["config"]), "--episodes", "1"]
        argv += ["--num_envs", "1", "--seed", str(7 + k), "--quiet", "--json", str(out)]
        assert eval_cli.main(argv) == 0
        (episode,) = json.loads(out.read_text())["episodes"]
        assert episode["episode_seed"] == int(derive_seed(7 + k, 0, 0))
        ours.append(episode)
    assert [e["success"] for e in ours] == successes
    overall = info["overall"]
    assert overall["pc_success"] == pytest.approx(100 * sum(e["success"] for e in ours) / 4)
    # the same inputs, so the same actions: equal returns where lerobot's sum stops at the episode's
    # end (an episode that ends before the other of its batch also counts the next step's reward)
    assert all(abs(total) > 1e-3 for total in metrics["sum_rewards"])  # the policy moved
    for k, (total, mine) in enumerate(zip(metrics["sum_rewards"], ours)):
        if mine["length"] >= ours[k ^ 1]["length"]:
            assert total == pytest.approx(mine["episode_return"], rel=1e-5), k
    if policy == "state":  # a config whose recorder lists no environment_state: the trained dataset's names
        data = json.loads(tiny["config"].read_text())
        del data["env"]["dataset"]["lerobot"]["params"]["environment_state"]
        bare = tmp_path / "bare.json"
        bare.write_text(json.dumps(data))
        again = lerobot_eval({**tiny, "config": bare}, tmp_path / "again", monkeypatch)["per_task"][0]["metrics"]
        assert again["successes"] == metrics["successes"]
        assert again["sum_rewards"] == pytest.approx(metrics["sum_rewards"], rel=1e-6)


@pytest.mark.slow  # ~40 s on 2 cores: lerobot-train's loop with one evaluation of 2 episodes
def test_lerobot_train_evaluates_on_our_env(
    tiny: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capfd: pytest.CaptureFixture
) -> None:
    out = tmp_path / "train"
    flags = [f"--policy.{k}={'null' if v is None else str(v).lower()}" for k, v in TINY_ACT.items()]
    args = [
        *ENV_ARGS,
        f"--env.gym_config={tiny['config']}",
        f"--dataset.repo_id=local/{tiny['dataset'].name}",
        f"--dataset.root={tiny['dataset']}",
        "--dataset.video_backend=pyav",
        "--policy.type=act",
        *flags,
        f"--output_dir={out}",
        "--steps=2",
        "--batch_size=2",
        "--num_workers=0",
        "--eval_freq=2",
        "--save_freq=2",
        "--eval.n_episodes=2",
        "--eval.batch_size=2",
        "--seed=7",
        "--wandb.enable=false",
    ]
    lerobot("train", args, monkeypatch)
    log = capfd.readouterr()
    overall = [line for line in (log.out + log.err).splitlines() if "Suite overall aggregated: " in line]
    assert len(overall) == 1  # evaluated once, at step 2
    wins = [int(derive_seed(7 + k, 0, 0)) % 2 == 0 for k in range(2)]  # lerobot's episode seeds 7, 8
    assert f"'pc_success': {50.0 * sum(wins)}, 'n_episodes': 2" in overall[0]
    assert len(list((out / "eval" / "videos_step_000002").rglob("*.mp4"))) == 2


def test_an_unknown_task_names_the_available_ones() -> None:
    from embodichain_lerobot.lerobot_env import EmbodiChainEnv

    with pytest.raises(EnvConfigError) as err:
        EmbodiChainEnv(task="PushCub-v1")
    message = str(err.value)
    assert message.startswith("env.task: unknown task 'PushCub-v1'. Did you mean 'PushCube-v1'?")
    assert "Available tasks: " in message
    assert "PickFork-v1" in message


def test_the_env_config_describes_the_recorded_features(recorded: dict[str, Path]) -> None:
    from lerobot.configs.types import FeatureType
    from lerobot.envs.utils import env_to_policy_features

    from embodichain_lerobot.lerobot_env import EmbodiChainEnv

    cfg = EmbodiChainEnv(gym_config=str(recorded["config"]))
    assert cfg.type == "embodichain"
    assert cfg.fps == 25
    features = env_to_policy_features(cfg)
    assert {k: (v.type, v.shape) for k, v in features.items()} == {
        "action": (FeatureType.ACTION, (7,)),
        "observation.state": (FeatureType.STATE, (7,)),
        "observation.images.head": (FeatureType.VISUAL, (3, 12, 16)),
    }
    # the dataset's inputs policies read (observation.qvel and .qf are recorded too; no lerobot policy reads them)
    info = json.loads((recorded["dataset"] / "meta" / "info.json").read_text())["features"]
    assert {"observation.qvel", "observation.qf"} <= set(info)
    assert tuple(info["observation.state"]["shape"]) == features["observation.state"].shape
    h, w, c = info["observation.images.head"]["shape"]
    assert (c, h, w) == features["observation.images.head"].shape
    assert info["action"]["shape"] == [7]


def test_a_policy_input_the_env_lacks_stops_lerobot_eval_before_any_episode(
    recorded: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bad = save_policy(tmp_path / "bad", state=9, camera="wrist")
    with pytest.raises(EnvConfigError) as err:
        lerobot_eval({**recorded, "policy": bad}, tmp_path / "eval", monkeypatch)
    message = str(err.value)
    assert message.startswith(f"policy: the policy {bad} reads inputs the env does not give lerobot: ")
    assert "observation.images.wrist [3, 12, 16] is missing" in message
    assert "observation.state is [9] for the policy, [7] in the env" in message
    assert message.endswith("The env gives: observation.images.head [3, 12, 16], observation.state [7]")
    assert not (tmp_path / "eval").exists()


def test_an_env_without_camera_renders_its_scene_for_lerobots_videos(recorded: dict[str, Path], tmp_path: Path) -> None:
    """A state-only task (the cameras removed, as for a state policy): ``agent_pos`` only, and
    ``render()`` draws the scene from MuJoCo's free camera."""
    import numpy as np
    from lerobot.envs.factory import make_env

    from embodichain_lerobot.lerobot_env import EmbodiChainEnv

    data = json.loads(recorded["config"].read_text())
    data.pop("sensor")
    config = tmp_path / "state.json"
    config.write_text(json.dumps(data))
    cfg = EmbodiChainEnv(gym_config=str(config), max_steps=3)
    assert cfg.features_map == {"action": "action", "agent_pos": "observation.state"}
    vec = make_env(cfg, n_envs=1)["embodichain"][0]
    try:
        obs, _ = vec.reset(seed=[3])
        assert sorted(obs) == ["agent_pos"]
        assert obs["agent_pos"].shape == (1, 7)
        assert vec.call("_max_episode_steps") == (3,)
        assert vec.call("task_description") == ("reach forward",)
        assert vec.call("task") == (data["id"],)
        frame = vec.envs[0].render()
        assert frame.shape == (240, 320, 3)
        assert frame.dtype == np.uint8
        assert frame.std() > 1.0  # a picture, not a blank frame
    finally:
        vec.close()
