"""The PPO script: a tiny end-to-end run, GAE, the observation normaliser, the PNG plotter."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch

from embodichain_tasks.rl.png_plot import line_plot_png
from embodichain_tasks.rl.ppo import PPOConfig, Rollout, compute_gae, main
from embodichain_tasks.rl.ppo_utils import RunningNorm, flatten_obs

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_two_iterations_write_the_curve_plot_and_policy(tmp_path: Path, capsys) -> None:
    out = tmp_path / "ppo"
    code = main(
        [
            "--num_envs",
            "4",
            "--num_steps",
            "8",
            "--total_steps",
            "64",
            "--max_episode_steps",
            "5",
            "--hidden",
            "16",
            "--minibatches",
            "2",
            "--update_epochs",
            "1",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    curve = json.loads((out / "curve.json").read_text())
    assert [row["iteration"] for row in curve] == [1, 2]
    assert [row["env_steps"] for row in curve] == [32, 64]
    assert all(row["episodes"] >= 4 and row["mean_return"] is not None for row in curve)
    assert (out / "curve.csv").read_text().splitlines()[0].startswith("iteration,env_steps,wall_s")
    assert (out / "learning_curve.png").read_bytes()[:8] == PNG_MAGIC
    saved = torch.load(out / "policy.pt", weights_only=False)
    assert set(saved) == {"agent", "obs_norm", "config"}
    assert saved["config"]["num_envs"] == 4
    assert "mean return: first" in capsys.readouterr().out


def test_gae_matches_a_hand_computation() -> None:
    cfg = PPOConfig(gamma=0.5, gae_lambda=0.5)
    t, n = 3, 1
    batch = Rollout(
        obs=torch.zeros(t, n, 1),
        actions=torch.zeros(t, n, 1),
        logprobs=torch.zeros(t, n),
        rewards=torch.tensor([[1.0], [2.0], [3.0]]),
        dones=torch.tensor([[0.0], [1.0], [0.0]]),
        values=torch.tensor([[0.5], [1.0], [2.0]]),
    )
    compute_gae(batch, torch.tensor([4.0]), cfg)
    d2 = 3.0 + 0.5 * 4.0 - 2.0  # last step bootstraps from next_value
    d1 = 2.0 - 1.0  # episode ended at step 1
    d0 = 1.0 + 0.5 * 1.0 - 0.5
    a1 = d1
    a0 = d0 + 0.25 * a1
    assert torch.allclose(batch.advantages.flatten(), torch.tensor([a0, a1, d2]))
    assert torch.allclose(batch.returns, batch.advantages + batch.values)


def test_running_norm_and_flatten() -> None:
    obs = {
        "robot": {"qpos": torch.ones(4, 2), "qvel": torch.zeros(4, 2)},
        "goal": torch.arange(12.0).reshape(4, 3),
        "sensor": {"cam": torch.zeros(4, 8, 8, 3)},
    }
    flat = flatten_obs(obs)
    assert flat.shape == (4, 7)
    assert torch.equal(flat[:, :3], obs["goal"])
    norm = RunningNorm(7)
    x = torch.randn(1000, 7) * 3 + 5
    y = norm(x)
    assert y.mean(0).abs().max() < 0.1
    assert (y.std(0) - 1).abs().max() < 0.1


def test_png_plotter_draws_the_series(tmp_path: Path) -> None:
    x = np.arange(10.0)
    png = line_plot_png([x], [x**2], title="T", xlabel="X", ylabel="Y", labels=["SQ"], size=(200, 120))
    assert png[:8] == PNG_MAGIC
    import struct
    import zlib

    width, height = struct.unpack(">II", png[16:24])
    assert (width, height) == (200, 120)
    data = png[33:]
    length = struct.unpack(">I", data[:4])[0]
    raw = zlib.decompress(data[8 : 8 + length])
    pixels = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + width * 3)[:, 1:].reshape(height, width, 3)
    blue = (pixels == np.array([31, 119, 180], dtype=np.uint8)).all(-1)
    assert blue.sum() > 100, "the series is drawn"
