"""The order of ``EmbodiedEnv.step`` and ``reset`` phases, as docs/embodied_env.md lists them.

Every phase is observed from the outside (functors of each manager, task override
points, the simulation backend, the recorder), each appending ``(phase, elapsed_steps
of env 0)`` to one log, so the test fails when the code and the documented order part.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import torch

from core_testlib import ARM_ACTIVE, FlagEnv

from embodichain_core.managers import ActionTerm, ActionTermCfg, DatasetFunctor, DatasetFunctorCfg
from embodichain_core.managers.cfg import EventCfg, ObservationCfg, RewardCfg

DOCS = Path(__file__).resolve().parents[1] / "docs" / "embodied_env.md"


def _log(env: Any, phase: str) -> None:
    env.__dict__.setdefault("phases", []).append((phase, int(env.elapsed_steps[0])))


class LoggedTerm(ActionTerm):
    """``pre``: command = action + 0.25 (so the applied targets are recognisable)."""

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        _log(self._env, f"action_{self.cfg.mode}")
        return action + 0.25

    def action_bounds(self) -> tuple[torch.Tensor, torch.Tensor]:
        return -torch.ones(self.action_dim), torch.ones(self.action_dim)


class LoggedRecorder(DatasetFunctor):
    def record_step(self, obs: Any, action: Any, reward: Any, terminated: Any, truncated: Any, info: dict) -> None:
        _log(self._env, "record")

    def record_reset(self, obs: Any, env_ids: torch.Tensor) -> None:
        _log(self._env, "record_reset")

    def __call__(self, env: Any, env_ids: torch.Tensor) -> None:
        _log(env, "commit")


def interval_event(env: Any, env_ids: Any) -> None:
    _log(env, "interval")


def reset_event(env: Any, env_ids: Any) -> None:
    _log(env, "reset_event")


def observe(env: Any, obs: Any) -> torch.Tensor:
    _log(env, "observation")
    return torch.zeros(env.num_envs, 1)


def reward_term(env: Any, obs: Any, action: Any, info: dict) -> torch.Tensor:
    _log(env, "reward")
    return torch.zeros(env.num_envs)


class OrderEnv(FlagEnv):
    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        _log(self, "task_state")
        return super().compute_task_state(**kwargs)

    def check_truncated(self, obs: Any, info: dict) -> torch.Tensor:
        _log(self, "dones")
        return super().check_truncated(obs, info)


def make_order_env(make_env: Any, make_cfg: Any) -> Any:
    cfg = make_cfg(
        max_episode_steps=2,
        actions={"arm": ActionTermCfg(func=LoggedTerm), "post": ActionTermCfg(func=LoggedTerm, mode="post")},
        events={
            "tick": EventCfg(func=interval_event, mode="interval", interval_step=1),
            "on_reset": EventCfg(func=reset_event, mode="reset"),
        },
        observations={"probe": ObservationCfg(func=observe, mode="add", name="probe")},
        rewards={"r": RewardCfg(func=reward_term)},
        dataset={"rec": DatasetFunctorCfg(func=LoggedRecorder, save_failed_episodes=True)},
    )
    env = make_env(cfg, env_cls=OrderEnv)
    env.phases = []  # construction computed a first observation
    sim, scene, rng = env.sim, env.scene, env.rng
    step, scene_reset, begin = sim.step, scene.reset, rng.begin_episodes

    def physics(nstep: int = 1, env_ids: Any = None) -> list[int]:
        # the command of the pre term is applied before physics runs
        env.phases.append(("physics", int(env.elapsed_steps[0]), float(sim.ctrl[0, 0])))
        return step(nstep, env_ids)

    sim.step = physics
    scene.reset = lambda ids=None, keep_uids=(): (_log(env, "scene_reset"), scene_reset(ids, keep_uids=keep_uids))
    rng.begin_episodes = lambda ids, seeds=None: (_log(env, "episode_streams"), begin(ids, seeds))
    return env


RESET = ["commit", "episode_streams", "scene_reset", "reset_event", "observation", "task_state", "record_reset"]


def test_step_and_reset_phases_run_in_the_documented_order(make_env, make_cfg) -> None:
    env = make_order_env(make_env, make_cfg)
    env.reset()
    assert [p[0] for p in env.phases] == RESET
    env.phases.clear()
    env.step(torch.zeros(2, ARM_ACTIVE))
    names = [p[0] for p in env.phases]
    assert names == [
        "action_pre",
        "physics",
        "interval",
        "observation",
        "task_state",
        "reward",
        "action_post",
        "dones",
        "record",
    ]
    physics = env.phases[1]
    assert physics[2] == 0.25  # phase 2 (apply the command) ran before phase 3 (physics)
    counters = dict((p[0], p[1]) for p in env.phases)
    assert counters["interval"] == 0  # interval events see the counters before this step counts
    assert counters["observation"] == 1  # phase 5 (counters) runs before observations
    assert counters["record"] == 1


def test_autoreset_runs_the_reset_phases_after_recording(make_env, make_cfg) -> None:
    env = make_order_env(make_env, make_cfg)
    env.reset()
    env.step(torch.zeros(2, ARM_ACTIVE))
    env.phases.clear()
    _, _, _, truncated, info = env.step(torch.zeros(2, ARM_ACTIVE))
    names = [p[0] for p in env.phases]
    assert truncated.all()
    assert info["elapsed_steps"].tolist() == [2, 2]  # info holds the counters including this step
    assert names[:9] == [
        "action_pre",
        "physics",
        "interval",
        "observation",
        "task_state",
        "reward",
        "action_post",
        "dones",
        "record",
    ]
    assert names[9:] == RESET  # the autoreset (phase 12) is the last phase
    assert env.elapsed_steps.tolist() == [0, 0]


def test_the_docs_list_the_phases_of_the_code() -> None:
    text = DOCS.read_text()
    step = text[text.index("### `step(action)`") : text.index("### Actions")]
    titles = re.findall(r"^(\d+)\. \*\*([^*]+)\*\*", step, flags=re.M)
    assert [int(n) for n, _ in titles] == list(range(13))
    assert [t for _, t in titles] == [
        "Action check",
        "Action terms",
        "Apply the command",
        "Physics",
        "Interval events",
        "Counters",
        "Observations",
        "Task state and info",
        "Rewards",
        "Post action terms",
        "Dones",
        "Recording",
        "Autoreset",
    ]
    source = (Path(__file__).resolve().parents[1] / "embodichain_core" / "envs" / "embodied_env.py").read_text()
    body = source[source.index("    def step(") : source.index("    def reset(")]
    assert [int(n) for n in re.findall(r"# (\d+)\. ", body)] == list(range(13))


def test_the_docs_list_the_reset_phases_of_the_code() -> None:
    text = DOCS.read_text()
    reset = text[text.index("### `reset(seed=None, options=None)`") : text.index("### Partial resets")]
    titles = re.findall(r"^(\d+)\. \*\*([^*]+)\*\*", reset, flags=re.M)
    assert [t for _, t in titles] == [
        "Seed",
        "Envs to reset",
        "Dataset",
        "Episode streams",
        "Scene reset",
        "Reset events",
        "Manager resets",
        "Counters",
        "Observation",
    ]
    source = (Path(__file__).resolve().parents[1] / "embodichain_core" / "envs" / "embodied_env.py").read_text()
    body = source[source.index("    def reset(") : source.index("    # -- phases with more than a line")]
    assert [int(n) for n, _ in titles] == list(range(1, 10))
    assert [int(n) for n in re.findall(r"# (\d+)\. ", body)] == list(range(1, 10))
