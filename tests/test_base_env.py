"""``BaseEnv``: a task whose step is written in overrides, without managers.

The fixture task pushes a cart along a rail (a force action) to a target drawn per
episode from the env's episode streams; a drag force acts between physics steps (the
task's own ``step_physics``). It is checked with the project's env checker and
gymnasium's (through ``UnbatchedEnv`` and ``gym.make_vec``).
"""

from __future__ import annotations

import uuid
import warnings
from typing import Any, Iterator

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

from embodichain_core.config.errors import ConfigError
from embodichain_core.envs import BaseEnv, EmbodiedEnv, EnvCfg, register_env
from embodichain_core.gym_vector import UnbatchedEnv
from embodichain_core.sim.cfg import JointDrivePropertiesCfg, RigidObjectCfg, RobotCfg
from embodichain_core.sim.scene import Scene
from embodichain_core.sim.shapes import CubeCfg
from embodichain_core.testing.env_checks import check_batched_env

from core_testlib import ARM_ACTIVE

CART = (
    '<mujoco><worldbody><body name="cart" pos="0 0 0.1"><joint name="x" type="slide" axis="1 0 0" range="-1 1"/>'
    '<geom type="box" size="0.05 0.05 0.05" mass="1"/></body></worldbody></mujoco>'
)
DRAG = 10.0  # N per m/s, applied by the task between physics steps
LIMIT = 25


class CartReach(BaseEnv):
    """Push the cart (force in N) to ``target``; hitting the end of the rail fails."""

    def design_scene(self, scene: Scene) -> None:
        scene.add_robot(RobotCfg(uid="cart", mjcf=CART, drive_pros=JointDrivePropertiesCfg(drive_type="none")))
        self.target = torch.zeros(self.num_envs)
        self.force = torch.zeros(self.num_envs)

    def define_action_space(self) -> gym.spaces.Box:
        return gym.spaces.Box(-20.0, 20.0, shape=(1,), dtype=np.float32)

    def apply_action(self, action: torch.Tensor) -> None:
        self.force = action[:, 0].clone()

    def step_physics(self) -> list[int]:
        cart, diverged = self.scene["cart"], set()
        for _ in range(self.sim_steps_per_control):
            cart.set_qf((self.force - DRAG * cart.get_qvel()[:, 0])[:, None])
            diverged.update(self.scene.sim.step(1))
        return sorted(diverged)

    def get_obs(self, **kwargs: Any) -> dict:
        cart = self.scene["cart"]
        state = torch.cat([cart.get_qpos(), cart.get_qvel()], dim=1).float()
        return {"cart": state, "target": self.target[:, None].clone()}

    def compute_task_state(self, **kwargs: Any) -> tuple[torch.Tensor, torch.Tensor, dict]:
        cart = self.scene["cart"]
        x, v = cart.get_qpos()[:, 0].float(), cart.get_qvel()[:, 0].float()
        error = (x - self.target).abs()
        return (error < 0.02) & (v.abs() < 0.05), x.abs() > 0.95, {"error": error}

    def get_reward(self, obs: Any, action: Any, info: dict) -> torch.Tensor:
        return -info["metrics"]["error"]

    def reset_envs(self, env_ids: torch.Tensor) -> None:
        super().reset_envs(env_ids)  # the cart back to x = 0, at rest
        side = np.where(self.rng.random(env_ids) < 0.5, -1.0, 1.0)
        self.target[env_ids] = torch.from_numpy(side * self.rng.uniform(env_ids, 0.2, 0.5)).float()


def make(num_envs: int = 3, **kwargs: Any) -> CartReach:
    return CartReach(EnvCfg(num_envs=num_envs, seed=0, max_episode_steps=LIMIT, verbose=False), **kwargs)


@pytest.fixture
def env() -> Iterator[CartReach]:
    built = make()
    yield built
    built.close()


@pytest.fixture(scope="module")
def task_id() -> Iterator[str]:
    uid = f"EcBaseCart{uuid.uuid4().hex[:8]}-v0"
    register_env(uid, max_episode_steps=LIMIT)(CartReach)
    yield uid
    gym.envs.registry.pop(uid, None)


def test_passes_the_project_env_checker(env: CartReach) -> None:
    check_batched_env(env, steps=5)
    assert env.single_observation_space["cart"].shape == (2,)
    assert env.action_space.shape == (3, 1)
    assert not hasattr(env, "event_manager")  # no managers


def test_passes_gymnasium_check_env_and_make_vec(task_id: str) -> None:
    single = UnbatchedEnv(gym.make(task_id, verbose=False))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # the checker's advice on infinite Box bounds
            check_env(single, skip_render_check=True)
    finally:
        single.close()
    venv = gym.make_vec(task_id, num_envs=2, vectorization_mode="sync", verbose=False)
    try:
        obs, _ = venv.reset(seed=1)
        assert obs["cart"].shape == (2, 2)
        _, reward, terminated, truncated, _ = venv.step(np.zeros((2, 1), np.float32))
        assert reward.shape == terminated.shape == truncated.shape == (2,)
    finally:
        venv.close()
    batched = gym.make_vec(task_id, num_envs=4, verbose=False)  # the batched env itself
    assert isinstance(batched.unwrapped, CartReach)
    assert batched.unwrapped.num_envs == 4
    assert batched.unwrapped.max_episode_steps == LIMIT
    batched.close()


def test_time_limit_and_same_step_autoreset(env: CartReach) -> None:
    assert env.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    env.reset(seed=0)
    first_targets = env.target.clone()
    for step in range(1, LIMIT + 1):
        obs, reward, terminated, truncated, info = env.step(torch.zeros(1))
        assert reward.dtype == torch.float32
        assert torch.equal(reward, -info["metrics"]["error"])
        assert not terminated.any()
        assert truncated.tolist() == [step == LIMIT] * 3
    assert info["_final_obs"].all()
    assert info["elapsed_steps"].tolist() == [LIMIT] * 3
    assert torch.equal(info["final_obs"]["target"][:, 0], first_targets)
    assert env.elapsed_steps.tolist() == [0, 0, 0]
    assert not torch.equal(obs["target"][:, 0], first_targets)  # the new episodes' targets


def test_termination_and_ignore_terminations(env: CartReach) -> None:
    env.reset(seed=0)
    push = torch.tensor([[20.0], [0.0], [0.0]])  # env 0 runs into the end of the rail
    for _ in range(LIMIT):
        _, _, terminated, truncated, info = env.step(push)
        if terminated.any():
            break
    assert terminated.tolist() == [True, False, False]
    assert not truncated.any()
    assert info["final_info"]["fail"].tolist() == [True, False, False]
    assert env.elapsed_steps[0] == 0  # only env 0 was reset
    assert env.elapsed_steps[1] > 0
    endless = make(ignore_terminations=True)
    endless.reset(seed=0)
    for _ in range(LIMIT - 1):
        _, _, terminated, truncated, info = endless.step(push)
        assert not terminated.any()
        assert not truncated.any()
    assert bool(info["fail"][0])  # failing, yet only the time limit ends the episode
    endless.close()


def test_the_task_physics_runs_between_physics_steps(env: CartReach) -> None:
    env.reset(seed=0)
    for _ in range(10):  # 0.4 s of a 2 N push on 1 kg: 0.8 m/s without the drag
        obs, *_ = env.step(torch.full((1,), 2.0))
    speed = obs["cart"][:, 1]
    assert torch.allclose(speed, torch.full((3,), 2.0 / DRAG), atol=0.01)  # the drag's terminal speed


def test_seeding_and_episode_replay(env: CartReach) -> None:
    def rollout(e: CartReach, seed: int) -> torch.Tensor:
        obs, _ = e.reset(seed=seed)
        for a in torch.linspace(-5.0, 5.0, 6):
            obs, *_ = e.step(a.reshape(1))
        return torch.cat([obs["cart"], obs["target"]], dim=1)

    other = make()
    try:
        assert torch.equal(rollout(env, 7), rollout(other, 7))
        assert not torch.equal(rollout(env, 7), rollout(other, 8))
    finally:
        other.close()
    env.reset(seed=3)
    seed, target = int(env.episode_seeds[1]), float(env.target[1])
    env.reset(options={"reset_ids": [2], "episode_seeds": [seed]})  # env 1's episode on env 2
    assert float(env.target[2]) == target


def test_bad_actions_and_configs_are_clear_errors(env: CartReach) -> None:
    with pytest.raises(ValueError, match=r"expected shape \(3, 1\)"):
        env.step(torch.zeros(3, 2))
    with pytest.raises(ConfigError, match="sim_steps_per_control"):
        make(sim_steps_per_control=0)
    with pytest.raises(ConfigError, match="Did you mean 'max_episode_steps'"):
        make(max_episode_step=3)


def test_missing_overrides() -> None:
    class NoScene(BaseEnv):
        pass

    with pytest.raises(NotImplementedError, match="NoScene must override design_scene"):
        NoScene(EnvCfg(verbose=False))

    class DiscreteCart(CartReach):
        closed = 0

        def define_action_space(self) -> Any:
            return gym.spaces.Discrete(3)

        def close(self) -> None:
            type(self).closed += 1
            super().close()

    with pytest.raises(TypeError, match="define_action_space must return a 1-D gym.spaces.Box"):
        DiscreteCart(EnvCfg(verbose=False))
    assert DiscreteCart.closed == 1  # a failed build closes what it opened


class LoggedArm(EmbodiedEnv):
    """Extends each of BaseEnv's overrides (``super()`` first) and logs the call; steps its
    physics one step at a time, holding the arm's joint efforts at zero between steps."""

    def _log(self, *entry: Any) -> None:
        self.__dict__.setdefault("log", []).append(entry)

    def check_cfg(self) -> None:
        super().check_cfg()
        self._log("check_cfg")

    def design_scene(self, scene: Scene) -> None:
        super().design_scene(scene)
        scene.add_rigid_object(RigidObjectCfg(uid="marker", shape=CubeCfg(size=[0.02] * 3), init_pos=(1.0, 1.0, 0.02)))
        self._log("design_scene")

    def on_scene_built(self) -> None:
        super().on_scene_built()
        self._log("on_scene_built", self.event_manager is not None)

    def define_action_space(self) -> gym.spaces.Box:
        space = super().define_action_space()
        self._log("define_action_space", space.shape)
        return space

    def apply_action(self, command: Any) -> None:
        super().apply_action(command)
        self._log("apply_action", command.clone())

    def step_physics(self) -> torch.Tensor:
        diverged = torch.zeros(self.num_envs, dtype=torch.bool)
        for _ in range(self.sim_steps_per_control):
            self.robot.set_qf(torch.zeros(self.num_envs, self.robot.dof))
            diverged |= self.sim.advance(1).cpu()
            self._log("physics_step")
        return diverged

    def reset_envs(self, env_ids: torch.Tensor) -> None:
        super().reset_envs(env_ids)
        self._log("reset_envs", env_ids.tolist())


def test_embodied_env_honours_the_base_env_overrides_of_a_subclass(make_env, make_cfg) -> None:
    env = make_env(make_cfg(max_episode_steps=2, sim_steps_per_control=3), env_cls=LoggedArm)
    assert isinstance(env, BaseEnv)
    assert [e[0] for e in env.log] == ["check_cfg", "design_scene", "on_scene_built", "define_action_space"]
    assert env.log[2][1]  # the managers exist once the scene is built
    assert env.log[3][1] == (ARM_ACTIVE,)
    assert "marker" in env.scene.rigid_objects  # an entity added by code next to the config's
    env.log.clear()
    env.reset(options={"reset_ids": [1]})
    assert env.log == [("reset_envs", [1])]
    env.log.clear()
    target = torch.full((2, ARM_ACTIVE), 0.1)
    env.step(target)
    assert [e[0] for e in env.log] == ["apply_action", "physics_step", "physics_step", "physics_step"]
    assert torch.equal(env.log[0][1], target)
    assert env.elapsed_steps.tolist() == [1, 1]
    env.log.clear()
    _, _, _, truncated, _ = env.step(target)  # the time limit: the autoreset calls reset_envs
    assert truncated.all()
    assert env.log[-1] == ("reset_envs", [0, 1])


def test_summary_lists_the_scene(capsys: pytest.CaptureFixture[str]) -> None:
    CartReach(EnvCfg(num_envs=2, seed=0)).close()
    out = capsys.readouterr().out
    assert "Environment initialized: CartReach" in out
    assert "Robots  cart" in out
    assert "Managers" not in out


def test_the_shared_generators_are_seeded_from_cfg_seed() -> None:
    draws = []
    for _ in range(2):
        built = make(num_envs=2)
        assert built.np_random_seed == built.cfg.seed == 0  # gymnasium's own generator, reported as seeded
        draws.append((built.np_random.random(3).tolist(), torch.rand(3, generator=built.generator).tolist()))
        built.reset(seed=5)
        assert built.np_random_seed == 5
        draws.append((built.np_random.random(3).tolist(), torch.rand(3, generator=built.generator).tolist()))
        built.close()
    assert draws[0] == draws[2]
    assert draws[1] == draws[3]
    assert draws[0] != draws[1]
