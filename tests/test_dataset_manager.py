"""DatasetManager through the env loop: per-step recording, committing successful
episodes (or all with save_failed_episodes), discarding, finalize."""

from __future__ import annotations

from typing import Any, Optional

import pytest
import torch

from core_testlib import FlagEnv, zero_action

from embodichain_core.managers import DatasetFunctor, DatasetFunctorCfg
from embodichain_core.managers.manager_base import functor_path_of


class EpisodeRecorder(DatasetFunctor):
    """Buffers one frame per env per step; commits finished episodes into ``saved``."""

    def __init__(self, cfg: Any, env: Any):
        super().__init__(cfg, env)
        self.frames: list[list] = [[] for _ in range(env.num_envs)]
        self.saved: list[tuple[int, int, str]] = []  # (env id, frames, tag)
        self.discarded: list[tuple[int, int]] = []
        self.dropped: dict[int, list] = {}
        self.resets: list[list[int]] = []
        self.first_obs: list[list[int]] = []
        self.finalized = 0

    def record_step(
        self, obs: Any, action: Any, reward: torch.Tensor, terminated: torch.Tensor, truncated: torch.Tensor, info: dict
    ) -> None:
        for i in range(self.num_envs):
            self.frames[i].append((obs["robot"]["qpos"][i].clone(), bool(terminated[i]), bool(truncated[i])))

    def record_reset(self, obs: Any, env_ids: torch.Tensor) -> None:
        self.first_obs.append(env_ids.tolist())

    def __call__(self, env: Any, env_ids: torch.Tensor, tag: str = "demo") -> None:
        for i in env_ids.tolist():
            if self.frames[i]:  # zero-length episodes (the first reset) are skipped
                self.saved.append((i, len(self.frames[i]), tag))
            self.frames[i] = []

    def discard(self, env_ids: torch.Tensor) -> None:
        for i in env_ids.tolist():
            if self.frames[i]:
                self.discarded.append((i, len(self.frames[i])))
                self.dropped[i] = self.frames[i]
            self.frames[i] = []

    def reset(self, env_ids: Optional[torch.Tensor] = None) -> None:
        self.resets.append(torch.as_tensor(env_ids).tolist())

    def finalize(self) -> Optional[str]:
        self.finalized += 1
        return f"/data/{self.cfg.params.get('tag', 'demo')}"


class BrokenFinalize(EpisodeRecorder):
    def finalize(self) -> Optional[str]:
        self.finalized += 1
        raise OSError("disk full")


def make_recording_env(make_env: Any, make_cfg: Any, save_failed: bool = False, **overrides: Any) -> Any:
    cfg = make_cfg(
        dataset={"rec": DatasetFunctorCfg(func=EpisodeRecorder, params={"tag": "t"}, save_failed_episodes=save_failed)},
        **overrides,
    )
    env = make_env(cfg, env_cls=FlagEnv)
    return env, env.dataset_manager.get_functor("rec")


def steps(env: Any, n: int) -> None:
    for _ in range(n):
        env.step(zero_action(env))


def test_commits_successful_episodes_only(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg)
    assert not env.dataset_manager.save_failed_episodes
    env.reset()
    assert rec.saved == []
    assert rec.discarded == []
    steps(env, 3)
    env.success_flags[0] = True
    env.step(zero_action(env))  # env 0 succeeds at its 4th step and is auto-reset
    env.success_flags[0] = False
    assert rec.saved == [(0, 4, "t")]
    assert rec.frames[0] == []
    assert len(rec.frames[1]) == 4
    env.fail_flags[1] = True
    env.step(zero_action(env))  # env 1 fails at its 5th step: dropped
    assert rec.saved == [(0, 4, "t")]
    assert rec.discarded == [(1, 5)]
    assert rec.first_obs[-2:] == [[0], [1]]
    assert rec.resets[-2:] == [[0], [1]]


def test_recorded_step_sees_the_terminal_frame(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg, max_episode_steps=3)
    env.reset()
    steps(env, 2)
    env.step(torch.full((2, 7), 0.2))
    # the truncated third frame was recorded before the auto-reset, then discarded (not a success)
    assert rec.discarded == [(0, 3), (1, 3)]
    assert [f[2] for f in rec.dropped[0]] == [False, False, True]
    assert rec.frames == [[], []]


def test_save_failed_episodes_commits_every_finished_episode(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg, save_failed=True, max_episode_steps=3)
    assert env.dataset_manager.save_failed_episodes
    env.reset()
    env.fail_flags[1] = True
    env.step(zero_action(env))
    env.fail_flags[1] = False
    assert rec.saved == [(1, 1, "t")]
    steps(env, 2)  # env 0 is truncated at step 3
    assert rec.saved == [(1, 1, "t"), (0, 3, "t")]
    assert rec.discarded == []


def test_manual_reset_commits_only_envs_in_a_successful_state(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg)
    env.reset()
    steps(env, 2)
    env.success_flags[1] = True
    env.reset()
    assert rec.saved == [(1, 2, "t")]
    assert rec.discarded == [(0, 2)]


def test_save_data_false_discards_even_successful_episodes(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg)
    env.reset()
    steps(env, 2)
    env.success_flags[:] = True
    env.reset(options={"save_data": False})
    assert rec.saved == []
    assert rec.discarded == [(0, 2), (1, 2)]


def test_finalize_is_idempotent_and_never_commits_partial_episodes(make_env, make_cfg) -> None:
    env, rec = make_recording_env(make_env, make_cfg)
    env.reset()
    steps(env, 3)
    env.close()
    assert rec.finalized == 1
    assert rec.saved == []  # the live episodes are not committed
    env.close()
    assert rec.finalized == 1
    assert env.dataset_manager.finalize() == ["/data/t"]
    assert rec.finalized == 1


def test_finalize_attempts_every_recorder_and_reraises_one_error_marked(make_env, make_cfg) -> None:
    cfg = make_cfg(
        dataset={
            "broken": DatasetFunctorCfg(func=BrokenFinalize),
            "ok": DatasetFunctorCfg(func=EpisodeRecorder, params={"tag": "ok"}),
        }
    )
    env = make_env(cfg, env_cls=FlagEnv)
    broken, ok = env.dataset_manager.get_functor("broken"), env.dataset_manager.get_functor("ok")
    with pytest.raises(OSError, match="disk full") as err:  # the recorder's own error, as it is
        env.close()
    assert functor_path_of(err.value) == "env.dataset.broken"
    assert broken.finalized == 1
    assert ok.finalized == 1
    env.close()  # idempotent: no second attempt
    assert broken.finalized == 1


def test_finalize_errors_of_several_recorders_are_raised_together(make_env, make_cfg) -> None:
    cfg = make_cfg(dataset={"a": DatasetFunctorCfg(func=BrokenFinalize), "b": DatasetFunctorCfg(func=BrokenFinalize)})
    env = make_env(cfg, env_cls=FlagEnv)
    with pytest.raises(RuntimeError, match=r"2 recorders: env\.dataset\.a: OSError: disk full; env\.dataset\.b"):
        env.close()


def test_dataset_params_are_checked(make_env, make_cfg) -> None:
    from embodichain_core.config.errors import ConfigError

    with pytest.raises(ConfigError, match=r"env\.dataset\.rec\.params\.tga"):
        make_env(make_cfg(dataset={"rec": DatasetFunctorCfg(func=EpisodeRecorder, params={"tga": "x"})}))


def test_plain_metadata_next_to_recorders_is_ignored(make_env, make_cfg) -> None:
    env = make_env(
        make_cfg(
            dataset={"robot_meta": {"robot_type": "arm"}, "rec": {"func": EpisodeRecorder, "params": {"tag": "d"}}}
        )
    )
    assert env.dataset_manager.active_functors == ["rec"]


def test_filter_dataset_saving_disables_the_manager(make_env, make_cfg) -> None:
    env = make_env(
        make_cfg(filter_dataset_saving=True, dataset={"rec": DatasetFunctorCfg(func=EpisodeRecorder)}), env_cls=FlagEnv
    )
    assert env.dataset_manager is None
    env.reset()
    env.success_flags[:] = True
    env.step(zero_action(env))  # finished episodes with no manager: nothing to do
    env.close()


class PickyRecorder(EpisodeRecorder):
    def __init__(self, cfg: Any, env: Any) -> None:
        from embodichain_core.config.errors import ConfigError

        raise ConfigError("params.tag", "must name a writable place")


def test_a_constructor_error_relative_to_the_params_gets_the_entry_path(make_env, make_cfg) -> None:
    from embodichain_core.config.errors import ConfigError

    with pytest.raises(ConfigError) as err:
        make_env(make_cfg(dataset={"rec": DatasetFunctorCfg(func=PickyRecorder, params={"tag": "t"})}))
    assert err.value.path == "env.dataset.rec.params.tag"
    assert "must name a writable place" in str(err.value)


class SuccessOnlyInInfo(FlagEnv):
    """``is_task_success`` never holds: only the terminal step's ``info["success"]`` says so."""

    def is_task_success(self, **kwargs: Any) -> torch.Tensor:
        return torch.zeros(self.num_envs, dtype=torch.bool)


def test_an_episode_that_ended_in_success_is_committed(make_env, make_cfg) -> None:
    cfg = make_cfg(dataset={"rec": DatasetFunctorCfg(func=EpisodeRecorder, params={"tag": "t"})})
    env = make_env(cfg, env_cls=SuccessOnlyInInfo)
    rec = env.dataset_manager.get_functor("rec")
    env.reset()
    env.success_flags[1] = True
    env.step(zero_action(env))  # env 1 terminates in success and is auto-reset in this step
    assert rec.saved == [(1, 1, "t")]
